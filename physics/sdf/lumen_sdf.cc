#include "physics/sdf/lumen_sdf.h"

namespace pcisim::physics {

SignedDistanceField build_lumen_sdf(const anatomy::VesselTree& tree, double spacing_m,
                                    const anatomy::LumenMeshSpec& mesh_spec) {
  SdfBuildSpec spec;
  spec.spacing_m = spacing_m;
  spec.padding_m = 1e-3;
  return SignedDistanceField::build(anatomy::loft_lumen(tree, mesh_spec), spec);
}

}  // namespace pcisim::physics
