#pragma once
// The one call a scene needs for wall contact: the vessel tree's lumen (every branch, the aorta
// included) lofted into closed tubes and turned into their union's signed distance field.
#include "physics/sdf/signed_distance_field.h"
#include "anatomy/vessel/lumen_mesh.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::physics {

// spacing_m: grid spacing (VesselContactParams::sdf_spacing_m); padding 1 mm, band 4 cells
SignedDistanceField build_lumen_sdf(const anatomy::VesselTree& tree, double spacing_m,
                                    const anatomy::LumenMeshSpec& mesh_spec = {});

}  // namespace pcisim::physics
