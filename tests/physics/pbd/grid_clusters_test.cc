// Cluster building: overlapping cubes cover every particle, and the ventricle stand-in is what
// the benchmark says it is.
#include "physics/pbd/grid_clusters.h"

#include <gtest/gtest.h>

#include <vector>

#include "physics/pbd/procedural_ventricle.h"

namespace pcisim::physics::pbd {
namespace {

TEST(GridClusters, OverlappingCubesCoverEveryParticle) {
  Eigen::Matrix3Xd x(3, 6 * 6 * 6);
  for (int i = 0; i < x.cols(); ++i) x.col(i) = 0.01 * Eigen::Vector3d(i % 6, (i / 6) % 6, i / 36);
  const auto clusters = grid_clusters(x, 0.02, 0.25);
  std::vector<int> membership(x.cols(), 0);
  for (const auto& c : clusters) {
    EXPECT_GE(c.size(), 4u);
    for (int i : c) ++membership[i];
  }
  int shared = 0;
  for (int m : membership) {
    EXPECT_GE(m, 1) << "every particle is matched somewhere";
    shared += m > 1;
  }
  EXPECT_GT(shared, x.cols() / 2) << "clusters overlap";
  // without overlap the cubes partition the lattice (cube edge chosen so no point is on a face)
  int total = 0;
  for (const auto& c : grid_clusters(x, 0.023, 0.0, 1)) total += static_cast<int>(c.size());
  EXPECT_EQ(total, x.cols());
}

TEST(GridClusters, TooFewParticlesGiveOneGlobalCluster) {
  Eigen::Matrix3Xd x(3, 3);
  x << 0, 1, 2, 0, 0, 0, 0, 0, 0;
  const auto clusters = grid_clusters(x, 0.1, 0.25);
  ASSERT_EQ(clusters.size(), 1u);
  EXPECT_EQ(clusters[0].size(), 3u);
}

TEST(ProceduralVentricle, IsAThickWallWithADrivenSeptum) {
  VentricleSpec spec;
  spec.spacing_m = 0.005;
  const Ventricle v = build_ventricle(spec);
  ASSERT_GT(v.system.particle_count(), 100);
  ASSERT_FALSE(v.driven.empty());
  for (int i : v.driven) {
    EXPECT_LT(v.rest_m(0, i), spec.septum_x_m);
    EXPECT_EQ(v.system.particles().state[i], ParticleState::kDriven);
    EXPECT_EQ(v.system.particles().inv_mass_per_kg[i], 0.0);
  }
  for (int i = 0; i < v.rest_m.cols(); ++i) {
    const Eigen::Vector3d p = v.rest_m.col(i);
    const double outer = (p.x() * p.x() + p.y() * p.y()) / (spec.radius_m * spec.radius_m) +
                         p.z() * p.z() / (spec.half_length_m * spec.half_length_m);
    EXPECT_LE(outer, 1.0 + 1e-12) << "inside the outer wall";
    EXPECT_LE(p.z(), spec.base_z_m + 1e-12) << "below the base";
  }
  EXPECT_GT(v.system.clusters().count(), 1);
  EXPECT_GT(v.system.distance_constraints().size(), static_cast<size_t>(v.system.particle_count()));
}

}  // namespace
}  // namespace pcisim::physics::pbd
