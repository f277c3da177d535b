// The SDF builder takes the stitched lumen (anatomy/vessel/lumen_surface.h) as it takes the
// lofted tubes, and the two fields agree near the wall.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include <fmt/format.h>
#include <numbers>

#include "anatomy/phantom/coronary_phantom.h"
#include "anatomy/vessel/lumen_surface.h"
#include "physics/sdf/lumen_sdf.h"
#include "physics/sdf/signed_distance_field.h"

namespace pcisim::physics {
namespace {

constexpr double kSpacingM = 0.2e-3;

// the analytic union of the coronaries' swept spheres (what the stitched surface approximates)
// (skip: a branch left out, or -1)
double union_distance_m(const anatomy::VesselTree& tree, const Eigen::Vector3d& p,
                        const anatomy::VesselBranch* skip = nullptr) {
  double f = std::numeric_limits<double>::infinity();
  for (const auto& b : tree.branches)
    if (&b != skip && b.name != "aorta")
      for (size_t i = 0; i + 1 < b.points.size(); ++i)
        f = std::min(f, anatomy::swept_sphere_distance_m(p, b.points[i].position_m, b.points[i].radius_m,
                                                         b.points[i + 1].position_m, b.points[i + 1].radius_m));
  return f;
}

Eigen::Vector3d perpendicular(const Eigen::Vector3d& t) {
  const Eigen::Vector3d a = std::abs(t.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return t.cross(a).normalized();
}

TEST(StitchedLumenSdfTest, PhantomFieldHasTheRightSignAndMatchesTheTubes) {
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({.seed = 1});
  // the coronaries (the aorta, a single wide tube, would take 60 % of the triangles and of the
  // build's time here and join nothing; the pipeline's test keeps it)
  const anatomy::TriangleMesh stitched = anatomy::stitch_lumen(tree, {.exclude = {"aorta"}});
  const auto t0 = std::chrono::steady_clock::now();
  const SignedDistanceField sdf = SignedDistanceField::build(stitched, kSpacingM, 1e-3);
  const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const SignedDistanceField tubes = build_lumen_sdf(tree, kSpacingM, {.exclude = {"aorta"}});

  int inside = 0, outside = 0, near_wall = 0;
  double max_diff_m = 0.0;
  std::string worst;
  for (const auto& b : tree.branches) {
    if (b.name == "aorta") continue;
    for (size_t i = 1; i + 1 < b.points.size(); i += 4) {
      const Eigen::Vector3d c = b.points[i].position_m;
      const double r = b.points[i].radius_m;
      EXPECT_LT(sdf.sample(c).distance_m, 0.0) << b.name << " point " << i;
      ++inside;
      const Eigen::Vector3d t = (b.points[i + 1].position_m - b.points[i - 1].position_m).normalized();
      const Eigen::Vector3d u = perpendicular(t), v = t.cross(u);
      for (int k = 0; k < 8; ++k) {
        const double a = k * std::numbers::pi / 4;
        const Eigen::Vector3d dir = std::cos(a) * u + std::sin(a) * v;
        // 1.5 radii off, where no other branch is near: outside
        const Eigen::Vector3d off = c + 1.5 * r * dir;
        if (union_distance_m(tree, off) > 0.25 * r) {
          EXPECT_GT(sdf.sample(off).distance_m, 0.0) << b.name << " point " << i;
          ++outside;
        }
        // near the wall, both fields
        for (double d : {-0.2e-3, 0.0, 0.2e-3}) {
          const Eigen::Vector3d p = c + (r + d) * dir;
          if (std::abs(union_distance_m(tree, p) - d) > 1e-6) continue;  // another branch is nearer
          // inside another branch too (a junction): the tubes' field sees the inner walls there
          // that the stitched surface no longer has, so the two rightly differ
          if (d < 0 && union_distance_m(tree, p, &b) < 0.1e-3) continue;
          const double diff_m = std::abs(sdf.sample(p).distance_m - tubes.sample(p).distance_m);
          if (diff_m > max_diff_m) {
            max_diff_m = diff_m;
            worst = fmt::format("{} point {} of {}, {:+.1f} mm off the wall, stitched {:.3f} mm, tubes {:.3f} mm",
                                b.name, i, b.points.size(), d * 1e3, sdf.sample(p).distance_m * 1e3,
                                tubes.sample(p).distance_m * 1e3);
          }
          ++near_wall;
        }
      }
    }
  }
  EXPECT_GT(inside, 200);
  EXPECT_GT(outside, 1000);
  EXPECT_GT(near_wall, 1000);
  // both approximate the same wall: the tubes' ring chords (0.05 mm) plus the grid's sag
  EXPECT_LT(max_diff_m, 0.1e-3);
  std::printf(
      "stitched %zu triangles, SDF build %.2f s, %.1f MB; %d/%d/%d points; max |stitched - tubes| "
      "near the wall %.1f um\n",
      stitched.triangles.size(), build_s, sdf.memory_bytes() / 1e6, inside, outside, near_wall, max_diff_m * 1e6);
  std::printf("worst: %s\n", worst.c_str());
}

}  // namespace
}  // namespace pcisim::physics
