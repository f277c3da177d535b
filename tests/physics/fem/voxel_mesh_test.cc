// The reference FEM's organ mesh: the voxels' cubes cut into conforming tets (their volume is
// the voxels' exactly, neighbours share nodes) and points embedded barycentrically.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>

#include "physics/fem/voxel_mesh.h"

namespace pcisim::physics::fem {
namespace {

TEST(VoxelMesh, CubesBecomeSharedNodeTetsOfTheVoxelsVolume) {
  // an L of four voxels of 2 mm, offset from the origin
  const double h = 2e-3;
  Eigen::Matrix3Xd centres(3, 4);
  centres << 0, h, 2 * h, 0,  //
      0, 0, 0, h,             //
      0, 0, 0, 0;
  centres.colwise() += Eigen::Vector3d(0.1e-3, 0.2e-3, 0.3e-3);
  const FemMesh m = voxel_tet_mesh(centres, h);
  EXPECT_EQ(m.tets.size(), 24u);
  // a row of three cubes has 16 corners, the fourth above the first adds 4 (it shares its face)
  EXPECT_EQ(m.rest_m.cols(), 20);
  double volume = 0.0;
  for (const auto& t : m.tets) {
    Eigen::Matrix3d e;
    for (int c = 0; c < 3; ++c) e.col(c) = m.rest_m.col(t[c + 1]) - m.rest_m.col(t[0]);
    volume += std::abs(e.determinant()) / 6.0;
  }
  EXPECT_NEAR(volume, 4 * h * h * h, 1e-18);
  // a point inside reproduces from its tet and weights; one outside goes to the nearest tet
  const StaticFem fem(m, neo_hookean_from_young(5e3, 0.3));
  const Eigen::Vector3d p = centres.col(3) + Eigen::Vector3d(0.3e-3, -0.2e-3, 0.1e-3);
  const Embedding e = embed(fem.mesh(), p);
  ASSERT_GE(e.tet, 0);
  EXPECT_GE(e.weights.minCoeff(), 0.0);
  EXPECT_NEAR(e.weights.sum(), 1.0, 1e-12);
  EXPECT_LT((embedded_position(fem.mesh(), fem.rest_positions(), e) - p).norm(), 1e-15);
  EXPECT_LT(embed(fem.mesh(), Eigen::Vector3d(1, 1, 1)).weights.minCoeff(), 0.0);
  EXPECT_THROW(voxel_tet_mesh(Eigen::Matrix3Xd(3, 0), h), std::invalid_argument);
}

}  // namespace
}  // namespace pcisim::physics::fem
