#pragma once
// Overlapping shape-matching clusters from cubical regions (soft-tissue paper, "Cluster-based
// deformation"): space is cut into cubes of edge cube_m, each cube grown by `overlap` of its
// edge on every side, and a cluster holds the particles inside its grown cube.
#include <Eigen/Core>
#include <vector>

namespace pcisim::physics::pbd {

// Clusters with fewer than min_members particles are dropped; a particle left in no cluster
// joins the cluster whose cube centre is nearest, so every particle is matched somewhere.
std::vector<std::vector<int>> grid_clusters(const Eigen::Matrix3Xd& x_m, double cube_m, double overlap,
                                            int min_members = 4);

}  // namespace pcisim::physics::pbd
