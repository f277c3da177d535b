#include "anatomy/vessel/lumen_surface.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <chrono>
#include <cmath>
#include <numbers>
#include <string>

#include "anatomy/mesh/mesh_io.h"
#include "anatomy/phantom/coronary_phantom.h"

namespace pcisim::anatomy {
namespace {

double enclosed_volume_m3(const TriangleMesh& m) {
  double v = 0.0;
  for (const auto& t : m.triangles) v += m.vertices_m[t[0]].dot(m.vertices_m[t[1]].cross(m.vertices_m[t[2]])) / 6.0;
  return v;
}

// V - E + F, with E = 3F / 2 on a closed mesh
long euler_characteristic(const TriangleMesh& m) {
  return long(m.vertices_m.size()) - long(3 * m.triangles.size() / 2) + long(m.triangles.size());
}

VesselBranch straight(const std::string& name, const Eigen::Vector3d& from, const Eigen::Vector3d& to, double r0_m,
                      double r1_m) {
  VesselBranch b;
  b.name = name;
  const int n = std::max(1, static_cast<int>(std::ceil((to - from).norm() / 0.5e-3)));
  for (int i = 0; i <= n; ++i) {
    const double s = double(i) / n;
    b.points.push_back({from + s * (to - from), r0_m + s * (r1_m - r0_m)});
  }
  return b;
}

double distance_to_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return (p - (a + t * (b - a))).norm();
}

TEST(LumenSurfaceTest, ConeSphereDistanceIsExactOutside) {
  const Eigen::Vector3d a(0, 0, 0), b(10e-3, 0, 0);
  // equal radii: a capsule
  EXPECT_NEAR(swept_sphere_distance_m({5e-3, 3e-3, 0}, a, 1e-3, b, 1e-3), 2e-3, 1e-12);
  EXPECT_NEAR(swept_sphere_distance_m({-2e-3, 0, 0}, a, 1e-3, b, 1e-3), 1e-3, 1e-12);
  EXPECT_NEAR(swept_sphere_distance_m({5e-3, 0, 0}, a, 1e-3, b, 1e-3), -1e-3, 1e-12);
  // a cone from 2 mm to 1 mm: the tangent line's normal is tilted by asin(0.1)
  const double sin_t = 0.1, cos_t = std::sqrt(1 - 0.01);
  const Eigen::Vector3d on_wall = Eigen::Vector3d(2e-3 * sin_t, 2e-3 * cos_t, 0);
  const Eigen::Vector3d normal(sin_t, cos_t, 0);
  for (double d : {0.0, 0.5e-3, 3e-3}) {
    const Eigen::Vector3d p = on_wall + 1e-3 * Eigen::Vector3d(cos_t, -sin_t, 0) + d * normal;
    EXPECT_NEAR(swept_sphere_distance_m(p, a, 2e-3, b, 1e-3), d, 1e-12) << d;
  }
  // one sphere inside the other: the larger one
  EXPECT_NEAR(swept_sphere_distance_m({0, 5e-3, 0}, a, 3e-3, {1e-3, 0, 0}, 1e-3), 2e-3, 1e-12);
}

TEST(LumenSurfaceTest, StraightBranchIsAClosedCapsule) {
  const double r = 1.5e-3, len = 10e-3;
  const Eigen::Vector3d a(0, 0.001, -0.002), b(len, 0.001, -0.002);
  VesselTree tree;
  tree.branches.push_back(straight("tube", a, b, r, r));
  StitchedLumenSpec spec;  // default spacing, 0.2 mm
  StitchedLumenStats stats;
  const TriangleMesh m = stitch_lumen(tree, spec, &stats);
  EXPECT_EQ(check_closed_manifold(m), "");
  EXPECT_EQ(count_components(m), 1);
  EXPECT_EQ(euler_characteristic(m), 2);
  double worst_m = 0.0;
  for (const auto& v : m.vertices_m) worst_m = std::max(worst_m, std::abs(distance_to_segment(v, a, b) - r));
  // linear interpolation of the distance along grid edges: the vertices sit within 2 % of r
  EXPECT_LT(worst_m, 0.02 * r) << "worst vertex off the capsule";
  const double capsule = std::numbers::pi * r * r * len + 4.0 / 3.0 * std::numbers::pi * r * r * r;
  const double vol = enclosed_volume_m3(m);
  EXPECT_GT(vol, 0.0) << "faces must wind outward";
  EXPECT_NEAR(vol, capsule, 0.02 * capsule);
  RecordProperty("worst_vertex_um", std::to_string(worst_m * 1e6));
  RecordProperty("volume_error_percent", std::to_string(100 * (vol - capsule) / capsule));
  std::printf("capsule r 1.5 mm, 0.2 mm grid: %zu triangles, worst vertex %.1f um, volume %+.2f %%, %zu bytes\n",
              m.triangles.size(), worst_m * 1e6, 100 * (vol - capsule) / capsule, stats.memory_bytes);
}

TEST(LumenSurfaceTest, SpacingFollowsTheSmallestRadiusWhenAsked) {
  VesselTree tree;
  tree.branches.push_back(straight("thin", {0, 0, 0}, {3e-3, 0, 0}, 0.4e-3, 0.4e-3));
  StitchedLumenSpec spec;
  spec.cells_per_min_radius = 4;
  StitchedLumenStats stats;
  const TriangleMesh m = stitch_lumen(tree, spec, &stats);
  EXPECT_NEAR(stats.spacing_m, 0.1e-3, 1e-12);
  EXPECT_EQ(check_closed_manifold(m), "");
  spec.exclude = {"thin"};
  EXPECT_TRUE(stitch_lumen(tree, spec).triangles.empty());
}

TEST(LumenSurfaceTest, YBifurcationIsOneClosedGenusZeroSurface) {
  VesselTree tree;
  const Eigen::Vector3d fork(10e-3, 0, 0);
  tree.branches.push_back(straight("trunk", {0, 0, 0}, fork, 1.5e-3, 1.4e-3));
  for (double side : {1.0, -1.0}) {
    VesselBranch child = straight(side > 0 ? "left" : "right", fork + Eigen::Vector3d(0, side * 0.3e-3, 0),
                                  fork + Eigen::Vector3d(7e-3, side * 4e-3, 1e-3), 1.1e-3, 0.9e-3);
    child.parent = 0;
    child.parent_point = static_cast<int>(tree.branches[0].points.size()) - 1;
    tree.branches.push_back(child);
  }
  const TriangleMesh m = stitch_lumen(tree, {});
  EXPECT_EQ(check_closed_manifold(m), "");
  EXPECT_EQ(count_components(m), 1);
  EXPECT_EQ(euler_characteristic(m), 2);
  EXPECT_GT(enclosed_volume_m3(m), 0.0);
}

// a shell of overlapping spheres encloses a void: its inner surface is dropped, the void filled
TEST(LumenSurfaceTest, AnEnclosedPocketIsDropped) {
  VesselTree tree;
  const int n = 200;
  for (int i = 0; i < n; ++i) {
    // a Fibonacci sphere of radius 3 mm, spheres of 0.8 mm about 0.75 mm apart
    const double z = 1.0 - 2.0 * (i + 0.5) / n, rho = std::sqrt(1.0 - z * z);
    const double a = i * std::numbers::pi * (3.0 - std::sqrt(5.0));
    VesselBranch b;
    b.name = "s" + std::to_string(i);
    b.points.push_back({3e-3 * Eigen::Vector3d(rho * std::cos(a), rho * std::sin(a), z), 0.8e-3});
    tree.branches.push_back(b);
  }
  StitchedLumenStats stats;
  const TriangleMesh m = stitch_lumen(tree, {}, &stats);
  EXPECT_EQ(stats.cavities_removed, 1u);
  EXPECT_EQ(check_closed_manifold(m), "");
  EXPECT_EQ(count_components(m), 1);
  EXPECT_EQ(euler_characteristic(m), 2);
  // the filled ball: close to a sphere of radius 3.8 mm (bumpy, so a little less)
  const double ball = 4.0 / 3.0 * std::numbers::pi * std::pow(3.8e-3, 3);
  EXPECT_NEAR(enclosed_volume_m3(m), ball, 0.1 * ball);
}

TEST(LumenSurfaceTest, CoronaryPhantomIsOneClosedGenusZeroSurface) {
  const VesselTree tree = make_coronary_phantom({.seed = 1});
  // the pipeline keeps the aorta: the coronaries join it, so one surface
  StitchedLumenStats stats;
  const auto t0 = std::chrono::steady_clock::now();
  const TriangleMesh all = stitch_lumen(tree, {}, &stats);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(check_closed_manifold(all), "");
  EXPECT_EQ(count_components(all), 1);
  EXPECT_EQ(euler_characteristic(all), 2);
  EXPECT_GT(enclosed_volume_m3(all), 0.0);
  std::printf(
      "phantom 1 with aorta, 0.2 mm: %zu triangles, %zu vertices, %.2f s, %.1f MB, %zu segments, "
      "%zu bricks sampled, %zu inside\n",
      all.triangles.size(), all.vertices_m.size(), seconds, stats.memory_bytes / 1e6, stats.segments,
      stats.bricks_sampled, stats.bricks_inside);
  // without the aorta the trees still meet: the phantom's LM and RCA both start on the aortic
  // centerline, 2 mm apart, so their first swept spheres overlap inside the (left out) aorta
  StitchedLumenSpec spec;
  spec.exclude = {"aorta"};
  const auto t1 = std::chrono::steady_clock::now();
  const TriangleMesh coronaries = stitch_lumen(tree, spec, &stats);
  const double seconds1 = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  EXPECT_EQ(check_closed_manifold(coronaries), "");
  EXPECT_EQ(count_components(coronaries), 1);
  EXPECT_EQ(euler_characteristic(coronaries), 2);
  std::printf("phantom 1 without aorta, 0.2 mm: %zu triangles, %.2f s, %.1f MB\n", coronaries.triangles.size(),
              seconds1, stats.memory_bytes / 1e6);
}

}  // namespace
}  // namespace pcisim::anatomy
