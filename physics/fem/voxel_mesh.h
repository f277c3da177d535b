#pragma once
// The reference FEM's mesh of an organ: Kuhn's six tets in every cube centred on an occupied
// voxel (a stair-stepped organ; nodes shared between neighbouring cubes), and points (fiducials)
// embedded in it by barycentric coordinates.
#include <Eigen/Core>

#include "physics/fem/static_fem.h"

namespace pcisim::physics::fem {

// voxel_centres_m: the occupied voxel centres of one regular grid of spacing voxel_m (as
// soft_tissue::TissueModel::interior_voxels_m gives them); throws std::invalid_argument when empty
FemMesh voxel_tet_mesh(const Eigen::Matrix3Xd& voxel_centres_m, double voxel_m);

struct Embedding {
  int tet = -1;                                       // the tet holding the point (or nearest to holding it)
  Eigen::Vector4d weights = Eigen::Vector4d::Zero();  // barycentric: p = sum w_i x_i
};

// the tet whose smallest barycentric coordinate of p is largest (>= 0: p is inside it)
Embedding embed(const FemMesh& mesh, const Eigen::Vector3d& p_m);
Eigen::Vector3d embedded_position(const FemMesh& mesh, const Eigen::VectorXd& x, const Embedding& e);

}  // namespace pcisim::physics::fem
