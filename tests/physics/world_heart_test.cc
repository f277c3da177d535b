// The beating default scene: heart, the tree riding its epicardium, pulsatile blood and the wire
// inside the moving lumen (issue: "vessels ride the heart").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "physics/blood/blood_chain_mail.h"
#include "physics/heart/beating_heart.h"
#include "physics/guidewire/rod_wire.h"
#include "physics/heart/heart_fit.h"
#include "physics/motion/vessel_skin.h"
#include "physics/sdf/sdf_kernels.h"
#include "physics/world.h"
#include "realtime/allocation_count.h"
#include "tests/common/shared_lumen.h"

namespace pcisim::physics {
namespace {

WorldSpec beating_spec() {
  WorldSpec s;
  s.heart_beat = HeartBeatParams{};
  s.vessel_motion = VesselMotionParams{};
  s.guidewire = GuidewireParams{};
  s.vessel_contact = VesselContactParams{};
  s.friction = FrictionParams{};
  s.blood_flow = BloodFlowParams{};
  return s;
}

// distance from p to the nearest triangle of the heart's epicardium as it is now
double epicardium_distance(const BeatingHeart& heart, const Eigen::Vector3d& p) {
  const auto& x = heart.positions_m();
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : heart.epicardium()) {
    int region = 0;
    auto v = [&](int i) { return sdf::V3{x(0, i), x(1, i), x(2, i)}; };
    const sdf::V3 q = sdf::closest_on_triangle({p.x(), p.y(), p.z()}, v(t[0]), v(t[1]), v(t[2]), &region);
    best = std::min(best, (Eigen::Vector3d(q.x, q.y, q.z) - p).norm());
  }
  return best;
}

// how far p is outside the lumen of the tree as it is now (negative inside): distance to the
// nearest moved centerline segment minus the radius there
double outside_lumen(const anatomy::VesselTree& rest, const VesselSkin& skin, const Eigen::Vector3d& p) {
  const auto pts = skin.points_m();
  const auto off = skin.branch_offsets();
  double best = std::numeric_limits<double>::infinity();
  for (size_t b = 0; b < rest.branches.size(); ++b) {
    const auto& br = rest.branches[b];
    for (size_t k = 0; k + 1 < br.points.size(); ++k) {
      const Eigen::Vector3d a = pts[off[b] + k], c = pts[off[b] + k + 1];
      const Eigen::Vector3d ab = c - a;
      const double u = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-18), 0.0, 1.0);
      const double r = br.points[k].radius_m + u * (br.points[k + 1].radius_m - br.points[k].radius_m);
      best = std::min(best, (p - a - u * ab).norm() - r);
    }
  }
  return best;
}

TEST(WorldHeart, BuildsTheHeartEffectsFirstAndOnlyWhenListed) {
  World w = test::make_world(beating_spec());
  std::vector<std::string> names;
  for (const auto& c : w.effect_costs()) names.push_back(c.name);
  ASSERT_GE(names.size(), 2u);
  EXPECT_EQ(names[0], "heart_beat");
  EXPECT_EQ(names[1], "vessel_motion");
  ASSERT_NE(w.heart_state(), nullptr);
  ASSERT_NE(w.vessel_skin(), nullptr);
  WorldSpec still = beating_spec();
  still.heart_beat.reset();
  still.vessel_motion.reset();
  World s = test::make_world(still);
  EXPECT_EQ(s.heart_state(), nullptr);
  EXPECT_EQ(s.vessel_skin(), nullptr);
  WorldSnapshot snap;
  s.step({});
  s.write_snapshot(snap);
  EXPECT_TRUE(snap.vessel_points_m.empty());
  EXPECT_EQ(snap.heart_phase, 0.0);
  WorldSpec orphan;
  orphan.vessel_motion = VesselMotionParams{};
  try {
    World bad = test::make_world(orphan);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "vessel_motion: needs heart_beat");
  }
}

// seed 1 is the tree the template was designed on; seed 3's LM and RCA sink into the template and
// the world fits the heart under them first
class WorldHeartSeeds : public ::testing::TestWithParam<uint32_t> {};

TEST_P(WorldHeartSeeds, TreeStaysOnTheEpicardiumOverAFullCycle) {
  WorldSpec spec;
  spec.anatomy.seed = GetParam();
  spec.heart_beat = HeartBeatParams{};
  spec.vessel_motion = VesselMotionParams{};
  World w = test::make_world(spec);  // the heart and the moving tree alone
  const VesselSkin& skin = *w.vessel_skin();
  const BeatingHeart& heart = *w.heart_state();
  const int lad = w.vessel_tree().find("LAD");
  const int rca = w.vessel_tree().find("RCA");
  ASSERT_GE(lad, 0);
  ASSERT_GE(rca, 0);
  // every 5th point of the LAD and RCA, fully attached ones
  std::vector<int> probe;
  for (int b : {lad, rca})
    for (int i = skin.branch_offsets()[b]; i < skin.branch_offsets()[b + 1]; i += 5)
      if (skin.ride_weight(i) == 1.0) probe.push_back(i);
  ASSERT_GT(probe.size(), 40u);
  std::vector<double> rest(probe.size());
  for (size_t k = 0; k < probe.size(); ++k) rest[k] = epicardium_distance(heart, skin.rest_points_m()[probe[k]]);
  const int steps = static_cast<int>(std::ceil(60.0 / heart.params().rate_bpm * 30.0)) + 1;  // a cycle at 30 Hz
  double worst = 0.0, moved = 0.0;
  for (int s = 0; s < steps; ++s) {
    w.step({});
    for (size_t k = 0; k < probe.size(); ++k) {
      const Eigen::Vector3d p = skin.points_m()[probe[k]];
      worst = std::max(worst, std::abs(epicardium_distance(heart, p) - rest[k]));
      moved = std::max(moved, (p - skin.rest_points_m()[probe[k]]).norm());
    }
  }
  // the stated bound: the tree's height above the epicardium changes by less than 0.5 mm while
  // the epicardium carries it several millimetres
  EXPECT_LT(worst, 5e-4) << "moved up to " << moved;
  EXPECT_GT(moved, 2e-3);
}

TEST_P(WorldHeartSeeds, HeartDoesNotSwallowTheTree) {
  WorldSpec spec;
  spec.anatomy.seed = GetParam();
  spec.heart_beat = HeartBeatParams{};
  spec.vessel_motion = VesselMotionParams{};
  World w = test::make_world(spec);
  const BeatingHeart& heart = *w.heart_state();
  const auto& x = heart.rest_positions_m();
  // radial clearance of every fully attached coronary point above the heart's epicardium at rest
  // (ray from the heart centre, Moller-Trumbore), minus the vessel's radius
  const VesselSkin& skin = *w.vessel_skin();
  const anatomy::VesselTree& tree = w.vessel_tree();
  double worst = 1e9;
  for (size_t b = 0; b < tree.branches.size(); ++b) {
    if (tree.branches[b].name == "aorta") continue;
    for (size_t k = 0; k < tree.branches[b].points.size(); ++k) {
      if (skin.ride_weight(skin.branch_offsets()[b] + static_cast<int>(k)) < 1.0) continue;
      const auto& point = tree.branches[b].points[k];
      const Eigen::Vector3d u = point.position_m.normalized();
      double radius = -1.0;
      for (const auto& t : heart.epicardium()) {
        const Eigen::Vector3d a = x.col(t[0]), e1 = x.col(t[1]) - a, e2 = x.col(t[2]) - a, p = u.cross(e2);
        const double det = e1.dot(p);
        if (std::abs(det) < 1e-18) continue;
        const double beta = -a.dot(p) / det;
        const Eigen::Vector3d q = (-a).cross(e1);
        const double gamma = u.dot(q) / det, t_hit = e2.dot(q) / det;
        if (t_hit > 0 && beta >= -1e-12 && gamma >= -1e-12 && beta + gamma <= 1 + 1e-12) radius = t_hit;
      }
      ASSERT_GT(radius, 0.0);
      worst = std::min(worst, point.position_m.norm() - point.radius_m - radius);
    }
  }
  EXPECT_GE(worst, -0.5e-3) << "seed " << GetParam();
  if (GetParam() == 1) {
    EXPECT_EQ(w.heart_fit().branches_lifted, 0) << "the template as designed";
  } else if (GetParam() == 3) {
    EXPECT_EQ(w.heart_fit().branches_lifted, 2) << "LM and RCA lifted";
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, WorldHeartSeeds, ::testing::Values(1u, 3u));

TEST(WorldHeart, WireStaysInsideTheMovingLumen) {
  World w = test::make_world(beating_spec());
  WorldSnapshot snap;
  InstrumentInput in;
  double worst = -1.0;
  int checked = 0;
  for (int k = 0; k < 150; ++k) {
    // the trainee script's opening: 8 mm, quarter turn, then on into the LAD
    in.insertion_m = std::min(0.008 + 0.0003 * k, 0.045);
    in.rotation_rad = k > 10 ? 1.5708 : 0.0;
    w.step(in);
    w.write_snapshot(snap);
    const ChainMailWire& wire = *w.guidewire_state();
    for (int i = wire.first_free_node(); i < wire.node_count(); i += 2) {
      worst = std::max(worst, outside_lumen(w.vessel_tree(), *w.vessel_skin(), snap.wire_nodes_m[i]));
      ++checked;
    }
  }
  ASSERT_GT(checked, 500);
  // the rest-frame contact keeps nodes inside within its margin; carrying them into the world
  // adds the blend's error (a rotating cross-section): stated bound 0.3 mm outside the wall
  EXPECT_LT(worst, 3e-4);
  EXPECT_GT(snap.heart_phase, 0.0);
  EXPECT_EQ(static_cast<int>(snap.vessel_points_m.size()), w.vessel_skin()->point_count());
}

TEST(WorldHeart, SnapshotCarriesTheWireWithItsVessel) {
  // hold the wire still in the LAD: its world tip moves with the beating heart
  World w = test::make_world(beating_spec());
  WorldSnapshot snap;
  InstrumentInput in;
  in.insertion_m = 0.02;
  for (int k = 0; k < 60; ++k) w.step(in);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  Eigen::Vector3d first;
  for (int k = 0; k < 30; ++k) {
    w.step(in);
    w.write_snapshot(snap);
    if (k == 0) first = snap.tip_m;
    const double d = (snap.tip_m - first).norm();
    lo = std::min(lo, d);
    hi = std::max(hi, d);
    EXPECT_LT((w.vessel_skin()->to_rest(snap.tip_m) - w.guidewire_state()->nodes_m().back()).norm(), 1e-5);
  }
  EXPECT_GT(hi - lo, 1e-3) << "the tip rides the heart";
}

// the rod in the beating scene, fed into the LAD as in WireStaysInsideTheMovingLumen, then held
// for two cycles; each step's world tip and the free nodes' distance outside the moving lumen
// the hub's force on a wire lying in a beating LAD: under the grip's 1 N refusal plus a step's change
constexpr double kHubBoundN = 1.5;
struct HeldRod {
  double worst_outside_m = -1.0;  // over the free nodes (every 2nd), feed and hold
  double peak_to_peak_m = 0.0;    // the tip's excursion while held
  double wall_force_n = 0.0;      // the wall's largest total force on the wire while held
  double hub_n = 0.0;             // the hub's largest axial force, feed and hold
  int hub_over_steps = 0;         // steps whose hub force exceeded kHubBoundN
  std::vector<Eigen::Vector3d> held_tip_m;
};
HeldRod run_held_rod(BeatCoupling coupling, RodContactScheme scheme = RodContactScheme::kProjection) {
  WorldSpec spec = beating_spec();
  spec.guidewire->model = GuidewireModel::kRod;
  spec.guidewire->segment_count = 300;
  spec.guidewire->beat_coupling = coupling;
  spec.guidewire->rod_contact = scheme;
  World w = test::make_world(spec);
  WorldSnapshot snap;
  InstrumentInput in;
  HeldRod r;
  const int held_steps = static_cast<int>(std::ceil(2.0 * 60.0 / spec.heart_beat->rate_bpm / spec.step_s));
  for (int k = 0; k < 150 + held_steps; ++k) {
    in.insertion_m = std::min(0.008 + 0.0003 * k, 0.045);
    in.rotation_rad = k > 10 ? 1.5708 : 0.0;
    w.step(in);
    w.write_snapshot(snap);
    const RodWire& wire = *w.rod_state();
    EXPECT_EQ(wire.recoveries(), 0);
    r.hub_n = std::max(r.hub_n, std::abs(wire.hub_axial_force_n()));
    r.hub_over_steps += std::abs(wire.hub_axial_force_n()) > kHubBoundN ? 1 : 0;
    for (int i = wire.first_free_node(); i < wire.node_count(); i += 2)
      r.worst_outside_m =
          std::max(r.worst_outside_m, outside_lumen(w.vessel_tree(), *w.vessel_skin(), snap.wire_nodes_m[i]));
    if (k >= 150) {
      r.held_tip_m.push_back(snap.tip_m);
      double f = 0.0;
      for (double n : wire.wall_force_n()) f += n;
      r.wall_force_n = std::max(r.wall_force_n, f);
    }
  }
  for (const auto& a : r.held_tip_m)
    for (const auto& b : r.held_tip_m) r.peak_to_peak_m = std::max(r.peak_to_peak_m, (a - b).norm());
  return r;
}

TEST(WorldHeart, TheBeatingWallPushesTheRod) {
  // beat_coupling contact: the rod lives in the world and the moving wall pushes it; kinematic:
  // it is solved at rest and carried. Both keep the wire inside the moving lumen, both tips move
  // with the heart, and they differ by how much the wire slides and lags inside the lumen
  // (docs/guidewire.md reports the figures)
  const HeldRod contact = run_held_rod(BeatCoupling::kContact);
  const HeldRod kinematic = run_held_rod(BeatCoupling::kKinematic);
  double rms = 0.0, worst = 0.0;
  for (size_t k = 0; k < contact.held_tip_m.size(); ++k) {
    const double d = (contact.held_tip_m[k] - kinematic.held_tip_m[k]).norm();
    rms += d * d;
    worst = std::max(worst, d);
  }
  rms = std::sqrt(rms / contact.held_tip_m.size());
  std::printf(
      "held rod over two beats: tip excursion %.2f mm (contact) / %.2f mm (kinematic); the tips differ by rms %.2f, "
      "max %.2f mm; worst outside the moving lumen %+.3f / %+.3f mm; wall force up to %.3g N (contact)\n",
      1e3 * contact.peak_to_peak_m, 1e3 * kinematic.peak_to_peak_m, 1e3 * rms, 1e3 * worst,
      1e3 * contact.worst_outside_m, 1e3 * kinematic.worst_outside_m, contact.wall_force_n);
  // the rod in the world is kept inside by its own contact (measured +0.075 mm against the
  // skin-moved tree); the carried rest-frame solution by the skin's blend, within the chain-mail's 0.3 mm
  EXPECT_LT(contact.worst_outside_m, 0.1e-3);
  EXPECT_LT(kinematic.worst_outside_m, 3e-4);
  // the wall carries the wire as far as the vessel moves (10 mm here), and the two schemes' tips
  // stay within a lumen's width of each other (measured 1.4 mm rms)
  EXPECT_GT(kinematic.peak_to_peak_m, 5e-3);
  EXPECT_NEAR(contact.peak_to_peak_m, kinematic.peak_to_peak_m, 0.25 * kinematic.peak_to_peak_m);
  EXPECT_LT(rms, 3e-3);
  EXPECT_GT(contact.wall_force_n, 0.0);
}

// The same with the wall inside the rod's solve (guidewire.rod_contact "solve", issue #33): the
// contact problem keeps the wire in the moving lumen, and the forces it gives stay a wire's. The
// run is chaotic at round-off; measured at other wire resolutions by a temporary patch: nothing
// more than the kinematic scheme's 0.3 mm outside the moving lumen (the lumen here is the
// skin-moved tree, the contact field an SDF sampled at 0.2 mm; the projection scheme's +0.075
// above); the wall's total force on a 0.014" wire lying in a beating LAD under 1 N; the hub's
// force under the grip's 1 N refusal plus a step's change, 1.5 N. Session 29, six resolutions
// (250-320): at most +0.136 mm, wall 0.08-0.26 N, hub 0.36-1.18 N. Session 30's end, twelve
// (240-350): +0.534 mm at 320 segments, over this bound (the tested 300: -0.052 mm), the rest
// within +0.138 mm, hub 0.16-1.37 N; open, not traced (docs/guidewire.md)
TEST(WorldHeart, WithTheWallInsideItsSolveTheRodStaysInTheBeatingLumenAndItsForcesStayAWires) {
  const HeldRod solve = run_held_rod(BeatCoupling::kContact, RodContactScheme::kSolve);
  std::printf(
      "held rod, wall inside the solve: worst outside %+.3f mm, wall force up to %.3g N, hub up to %.3g N (%d steps "
      "over %.1f N)\n",
      1e3 * solve.worst_outside_m, solve.wall_force_n, solve.hub_n, solve.hub_over_steps, kHubBoundN);
  EXPECT_LT(solve.worst_outside_m, 0.3e-3);
  EXPECT_GT(solve.wall_force_n, 0.0);
  EXPECT_LT(solve.wall_force_n, 1.0);
  EXPECT_EQ(solve.hub_over_steps, 0);
  EXPECT_LT(solve.hub_n, kHubBoundN);
  EXPECT_GT(solve.peak_to_peak_m, 5e-3) << "the wall carries the wire as the vessel moves";
}

TEST(WorldHeart, BloodDragMovesAnUnconstrainedWireDownstream) {
  // no wall: only the wire's own links and the blood act; the tip ends up further down the LM/LAD
  WorldSpec with_blood;
  with_blood.guidewire = GuidewireParams{};
  with_blood.blood_flow = BloodFlowParams{};
  with_blood.blood_flow->drift_gain = 0.2;
  WorldSpec without = with_blood;
  without.blood_flow.reset();
  World a(with_blood), b(without);
  InstrumentInput in;
  in.insertion_m = 0.012;
  for (int k = 0; k < 60; ++k) {
    a.step(in);
    b.step(in);
  }
  const auto na = a.guidewire_state()->nodes_m(), nb = b.guidewire_state()->nodes_m();
  const Eigen::Vector3d drift = na.back() - nb.back();
  // downstream: along the LM, away from the catheter exit
  const auto& lm = a.vessel_tree().branches[a.vessel_tree().find("LM")].points;
  const Eigen::Vector3d along = (lm.back().position_m - lm.front().position_m).normalized();
  EXPECT_GT(drift.dot(along), 1e-4) << drift.transpose();
}

TEST(WorldHeart, BeatingStepAllocatesNothing) {
  World w = test::make_world(beating_spec());
  WorldSpec rod_spec = beating_spec();
  rod_spec.guidewire->model = GuidewireModel::kRod;
  rod_spec.guidewire->beat_coupling = BeatCoupling::kContact;
  World rod_world = test::make_world(rod_spec);
  WorldSnapshot rod_snap;
  rod_world.step({});
  rod_world.write_snapshot(rod_snap);
  WorldSnapshot snap;
  InstrumentInput in;
  w.step(in);
  w.write_snapshot(snap);
  pcisim::realtime::AllocationCount count;
  for (int k = 0; k < 30; ++k) {
    in.insertion_m = 0.001 * k;
    w.step(in);
    w.write_snapshot(snap);
    rod_world.step(in);
    rod_world.write_snapshot(rod_snap);
  }
  EXPECT_EQ(count.allocations(), 0);
}

}  // namespace
}  // namespace pcisim::physics
