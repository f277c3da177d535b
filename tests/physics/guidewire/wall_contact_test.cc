// Wall contact (eq 15): a node outside the lumen or inside the wall margin goes back to depth
// epsilon, and in the coronary tree no free node ever ends a step outside by more than epsilon.
#include "physics/guidewire/wall_contact.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "physics/guidewire/sdf_lumen.h"
#include "physics/guidewire/tube_lumen.h"
#include "anatomy/phantom/coronary_phantom.h"
#include "tests/physics/guidewire/wire_test_support.h"
#include "tests/common/shared_lumen.h"

namespace pcisim::physics {
namespace {

// the half-space z < wall_z is lumen; the wall normal is +z
class PlaneLumen final : public LumenQuery {
 public:
  explicit PlaneLumen(double wall_z_m) : wall_z_m_(wall_z_m) {}
  WallSample sample(const Eigen::Vector3d& p) const override {
    WallSample s;
    s.distance_m = p.z() - wall_z_m_;
    s.normal = Eigen::Vector3d::UnitZ();
    return s;
  }

 private:
  double wall_z_m_;
};

GuidewireParams short_wire() {
  GuidewireParams p;
  p.length_m = 0.02;
  p.segment_count = 20;
  p.tip_length_m = 0.0;
  p.tip_angle_deg = 0.0;
  return p;
}

CatheterPath straight_catheter() {
  return CatheterPath({Eigen::Vector3d(-0.05, 0.0, 0.0), Eigen::Vector3d::Zero()});
}

TEST(WallContact, MovesNodesBackToDepthEpsilonAlongTheNormal) {
  ChainMailWire wire(short_wire(), straight_catheter());
  wire.begin_step(0.010, 0.0);
  VesselContactParams cp;
  PlaneLumen lumen(0.5e-3);
  WallContact contact(cp, lumen, wire.node_count());
  contact.begin_step();
  auto x = wire.mutable_nodes_m();
  const int k = wire.node_count() - 3;
  x[k].z() = 0.8e-3;                // 0.3 mm into the wall
  x[k + 1].z() = 0.5e-3 - 0.01e-3;  // inside, but within the margin
  const Eigen::Vector3d before_k = x[k], deep = x[k - 2];
  contact.project(wire);
  EXPECT_NEAR(x[k].z(), 0.5e-3 - cp.wall_margin_m, 1e-12);
  EXPECT_NEAR(x[k + 1].z(), 0.5e-3 - cp.wall_margin_m, 1e-12);
  EXPECT_DOUBLE_EQ(x[k].x(), before_k.x());  // only along the normal
  EXPECT_EQ(x[k - 2], deep);                 // nodes deep inside are left alone
  EXPECT_EQ(contact.touched()[k], 1);
  EXPECT_EQ(contact.touched()[k - 2], 0);
  EXPECT_NEAR(contact.pass_normal_m()[k], 0.3e-3 + cp.wall_margin_m, 1e-12);
}

TEST(WallContact, NoFreeNodeEndsAStepOutsideTheLumenByMoreThanTheMargin) {
  // the scripted sessions into the LAD and the LCx, checked after every step against the
  // world's own contact geometry (the SDF of the lofted lumen)
  for (double turn : {90.0, -90.0}) {
    World world = test::make_world(test::default_scene());
    test::BranchScript script;
    script.turn_deg = turn;
    const double eps = world.contact_state()->params().wall_margin_m;
    double worst = -1.0;
    for (double t = 0.0; t <= script.end_s(); t += test::default_scene().step_s) {
      world.step(script.at(t));
      const double d = test::worst_wall_distance_m(*world.guidewire_state(), *world.lumen());
      worst = std::max(worst, d);
      ASSERT_LE(d, eps + 1e-9) << "turn " << turn << " t " << t;
    }
    EXPECT_GT(worst, -eps - 1e-6);  // the wire did touch the wall
  }
}

TEST(WallContact, SdfLumenAgreesWithTheAnalyticTubesNearTheWall) {
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({1});
  const SdfLumen sdf(tree, 0.2e-3);
  const TubeLumen tubes(tree);
  // points across the LAD at its 100th centerline point
  const auto& lad = tree.branches[tree.find("LAD")];
  const Eigen::Vector3d c = lad.points[100].position_m;
  const Eigen::Vector3d t = (lad.points[101].position_m - lad.points[99].position_m).normalized();
  const Eigen::Vector3d side = t.unitOrthogonal();
  for (double off_mm : {0.0, 0.5, 1.0, 1.5, 2.0, 2.5}) {
    const Eigen::Vector3d p = c + off_mm * 1e-3 * side;
    const WallSample a = sdf.sample(p), b = tubes.sample(p);
    if (std::abs(b.distance_m) > 0.6e-3) continue;  // the SDF band
    EXPECT_NEAR(a.distance_m, b.distance_m, 0.1e-3) << off_mm;
    EXPECT_GT(a.normal.dot(b.normal), 0.9) << off_mm;
  }
}

// the union of capsules by looking at every one of them: what TubeLumen's bins and tree must give
double nearest_capsule_m(const anatomy::VesselTree& tree, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& b : tree.branches)
    for (size_t k = 0; k + 1 < b.points.size(); ++k) {
      const Eigen::Vector3d a = b.points[k].position_m, ab = b.points[k + 1].position_m - a;
      const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      const double r = b.points[k].radius_m + t * (b.points[k + 1].radius_m - b.points[k].radius_m);
      best = std::min(best, (p - (a + t * ab)).norm() - r);
    }
  return best;
}

TEST(TubeLumen, NearTheWallsAndAwayFromAllTubesTheAnswerIsTheNearestCapsule) {
  // within the band of a wall (1 mm) and where no tube is near (a bin of none, the tree's walk;
  // off the bins' grid): the signed distance of the nearest capsule, found by looking at all of
  // them. Farther out in a bin that lists tubes: a real tube's distance, never below the nearest
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({1});
  const TubeLumen tubes(tree);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.04, 0.04);
  const auto& lad = tree.branches[tree.find("LAD")];
  int near = 0, far = 0;
  for (int k = 0; k < 3000; ++k) {
    const auto& c = lad.points[static_cast<size_t>(k) % lad.points.size()].position_m;
    const double scale = k < 1500 ? 0.05 : 1.0;  // half of them within ~2 mm of the LAD
    const Eigen::Vector3d p = c + scale * Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng));
    const double want = nearest_capsule_m(tree, p);
    const WallSample got = tubes.sample(p);
    ASSERT_NEAR(got.normal.norm(), 1.0, 1e-12);
    ASSERT_GE(got.distance_m, want - 1e-12) << "point " << k;
    if (want < 1e-3) {
      ASSERT_NEAR(got.distance_m, want, 1e-12) << "point " << k;
      ++near;
    } else if (want > 20e-3) {
      // a bin lists a tube whose box grown by its radius and the band meets it: 20 mm out of
      // every coronary (radius < 3 mm, segments ~1 mm, bins of 3 mm) no bin lists one
      ASSERT_NEAR(got.distance_m, want, 1e-12) << "point " << k;
      ++far;
    }
  }
  EXPECT_GT(near, 100);
  EXPECT_GT(far, 500);
  // far outside the whole tree (off the bins)
  const Eigen::Vector3d out = lad.points[0].position_m + Eigen::Vector3d(0.5, -0.3, 0.2);
  EXPECT_NEAR(tubes.sample(out).distance_m, nearest_capsule_m(tree, out), 1e-12);
}

}  // namespace
}  // namespace pcisim::physics
