#pragma once
// Accuracy of an extracted lumen against exact truth: the symmetric surface distance of two
// meshes, and the Dice overlap of two vessel trees' lumens.
#include <string>
#include <vector>
#include "anatomy/mesh/triangle_mesh.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::modeling {

struct LumenScores {
  // over points sampled on both surfaces, each weighted by the area it stands for, pooled
  double mean_mm = 0;         // mean distance to the other surface (symmetric, ASSD)
  double hausdorff95_mm = 0;  // 95th percentile of those distances ("95 % Hausdorff")
  double max_mm = 0;          // the largest (Hausdorff, up to sampling)
  double reference_to_extracted_mean_mm = 0, extracted_to_reference_mean_mm = 0;
  int samples = 0;  // points sampled on both surfaces
};

// distances between the surfaces: points every ~sample_spacing_m on each mesh's triangles (each
// triangle cut into strips along its longest edge and the strips into pieces, all about the
// spacing across, a point in each piece weighted by its area), measured exactly to the nearest triangle of the other
// mesh through a bounding-volume hierarchy. NaN when either mesh has no triangle; throws std::invalid_argument for a
// spacing <= 0 or a triangle naming a missing vertex.
LumenScores score_lumen(const anatomy::TriangleMesh& reference, const anatomy::TriangleMesh& extracted,
                        double sample_spacing_m);

// Dice 2|A n B| / (|A| + |B|) of two trees' lumens, each the union over consecutive centerline
// points of a cone frustum with a ball of the point's radius at either end (a branch leaving its
// parent's point away from its own first point gets a piece joining the two). Voxel centres of a
// grid of spacing voxel_m anchored at the origin, kept in sparse 8^3 blocks, so only voxels near
// either tree are visited. NaN when both lumens are empty.
double dice_of_trees(const anatomy::VesselTree& a, const anatomy::VesselTree& b, double voxel_m,
                     const std::vector<std::string>& exclude = {"aorta"});

}  // namespace pcisim::modeling
