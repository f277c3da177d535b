// Hard cases (DESIGN.md): each provocation must leave no NaN, positions inside the anatomy's
// bounds and the chain-mail limits holding after every step; once it stops, the wire settles
// back inside the lumen within the wall margin.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "physics/guidewire/coulomb_friction.h"
#include "physics/guidewire/sdf_lumen.h"
#include "physics/guidewire/tube_lumen.h"
#include "physics/guidewire/wall_contact.h"
#include "anatomy/phantom/coronary_phantom.h"
#include "tests/physics/guidewire/wire_test_support.h"
#include "tests/common/shared_lumen.h"

namespace pcisim::physics {
namespace {

using test::BranchScript;
using test::check_limits;
using test::default_scene;

// free nodes stay within 150 mm of the heart's centre (the phantom spans about +-70 mm); nodes
// still in the catheter lie on its path
bool sane(const ChainMailWire& w) {
  const auto x = w.nodes_m();
  for (int i = 0; i < w.node_count(); ++i) {
    if (!x[i].allFinite()) return false;
    if (i >= w.first_free_node() && x[i].norm() > 0.15) return false;
  }
  return true;
}

// one step's worth of checks on a world
void expect_sound(const World& world, double t) {
  const ChainMailWire& w = *world.guidewire_state();
  ASSERT_TRUE(sane(w)) << "t " << t;
  const auto r = check_limits(w);
  ASSERT_EQ(r.bad_links, 0) << "t " << t << " length excess " << r.worst_length_ratio_excess << " shear excess "
                            << r.worst_shear_excess_rad;
  ASSERT_EQ(w.recoveries(), 0) << "t " << t;
  const LocalForceModel m = world.force_model();
  ASSERT_TRUE(std::isfinite(m.f0_n) && std::isfinite(m.k_n_per_m) && std::isfinite(m.t0_nm)) << "t " << t;
}

// holds the instrument still for 2 s and checks the wire settled inside the wall margin
void expect_settles(World& world, const InstrumentInput& hold) {
  for (double t = 0.0; t < 2.0; t += default_scene().step_s) world.step(hold);
  const ChainMailWire& w = *world.guidewire_state();
  EXPECT_TRUE(sane(w));
  EXPECT_EQ(check_limits(w).bad_links, 0);
  const double eps = world.contact_state()->params().wall_margin_m;
  EXPECT_LE(test::worst_wall_distance_m(w, *world.lumen()), eps + 1e-9);
}

bool in_subtree(const anatomy::VesselTree& tree, int branch, const char* root) {
  const int r = tree.find(root);
  for (int b = branch; b >= 0; b = tree.branches[b].parent) {
    if (b == r) return true;
  }
  return false;
}

TEST(GuidewireHardCases, PushingOneHundredMillimetresIntoADeadEnd) {
  // into the LCx, then 100 mm more over 10 s: the LCx (80 mm) and its marginals end well
  // before that, so the wire is driven into dead ends and has to buckle or be refused
  World world = test::make_world(default_scene());
  BranchScript script;
  script.turn_deg = -90.0;
  const double dt = default_scene().step_s;
  double t = 0.0;
  for (; t <= script.end_s(); t += dt) world.step(script.at(t));
  InstrumentInput in = script.at(script.end_s());
  const double start_m = in.insertion_m;
  for (double s = 0.0; s <= 10.0; s += dt) {
    in.insertion_m = start_m + 0.1 * std::min(s / 10.0, 1.0);
    in.insertion_rate_m_per_s = 0.01;
    world.step(in);
    expect_sound(world, t + s);
  }
  in.insertion_rate_m_per_s = 0.0;
  expect_settles(world, in);
}

TEST(GuidewireHardCases, FullPullBackAndReinsertion) {
  World world = test::make_world(default_scene());
  BranchScript script;
  const double dt = default_scene().step_s;
  for (double t = 0.0; t <= script.end_s(); t += dt) world.step(script.at(t));
  InstrumentInput in = script.at(script.end_s());
  const double start_m = in.insertion_m;
  for (double s = 0.0; s <= 2.0; s += dt) {  // all the way out in 2 s
    in.insertion_m = start_m * std::max(1.0 - s / 1.9, 0.0);
    world.step(in);
    expect_sound(world, s);
  }
  const ChainMailWire& w = *world.guidewire_state();
  EXPECT_EQ(w.first_free_node(), w.node_count());  // the whole wire is back in the catheter
  EXPECT_EQ(w.fed_length_m(), 0.0);
  EXPECT_LT((w.nodes_m().back() - w.path().exit_m()).norm(), 1e-9);
  // and it comes out again into the left main
  for (double s = 0.0; s <= 2.0; s += dt) {
    in.insertion_m = 0.015 * std::min(s / 1.5, 1.0);
    world.step(in);
    expect_sound(world, s);
  }
  WorldSnapshot snap;
  world.write_snapshot(snap);
  EXPECT_EQ(world.vessel_tree().branches[snap.tip_branch].name, "LM");
  expect_settles(world, in);
}

TEST(GuidewireHardCases, OneHundredTurnsOfRotation) {
  World world = test::make_world(default_scene());
  BranchScript script;
  const double dt = default_scene().step_s;
  for (double t = 0.0; t <= script.end_s(); t += dt) world.step(script.at(t));
  InstrumentInput in = script.at(script.end_s());
  const double start_rad = in.rotation_rad;
  for (double s = 0.0; s <= 20.0; s += dt) {  // 5 turns a second
    in.rotation_rad = start_rad + 200.0 * std::numbers::pi * std::min(s / 20.0, 1.0);
    in.rotation_rate_rad_per_s = 10.0 * std::numbers::pi;
    world.step(in);
    expect_sound(world, s);
  }
  in.rotation_rate_rad_per_s = 0.0;
  expect_settles(world, in);
  // the tip turned in place: still down the LAD (or in one of its side branches)
  WorldSnapshot snap;
  world.write_snapshot(snap);
  EXPECT_TRUE(in_subtree(world.vessel_tree(), snap.tip_branch, "LAD"))
      << world.vessel_tree().branches[snap.tip_branch].name;
}

TEST(GuidewireHardCases, TimeStepTenTimesLonger) {
  WorldSpec spec = default_scene();
  spec.step_s *= 10.0;  // 3 Hz: ten times the feed and turn per step
  World world = test::make_world(spec);
  BranchScript script;
  for (double t = 0.0; t <= script.end_s(); t += spec.step_s) {
    world.step(script.at(t));
    expect_sound(world, t);
    const double eps = world.contact_state()->params().wall_margin_m;
    ASSERT_LE(test::worst_wall_distance_m(*world.guidewire_state(), *world.lumen()), eps + 1e-9) << t;
  }
  WorldSnapshot snap;
  world.write_snapshot(snap);
  EXPECT_EQ(world.vessel_tree().branches[snap.tip_branch].name, "LAD");
}

TEST(GuidewireHardCases, NonFiniteInstrumentInputIsRejectedAndThePreviousSampleKept) {
  World world = test::make_world(default_scene());
  BranchScript script;
  const double dt = default_scene().step_s;
  double t = 0.0;
  for (; t <= 10.0; t += dt) world.step(script.at(t));
  WorldSnapshot before, after;
  world.write_snapshot(before);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const InstrumentInput good = script.at(t - dt);
  int sent = 0;
  for (int k = 0; k < 30; ++k, ++sent) {
    InstrumentInput bad = good;
    switch (k % 5) {
      case 0:
        bad.insertion_m = nan;
        break;
      case 1:
        bad.rotation_rad = inf;
        break;
      case 2:
        bad.insertion_rate_m_per_s = -inf;
        break;
      case 3:
        bad.rotation_rate_rad_per_s = nan;
        break;
      default:
        bad.insertion_m = 1e300;
        break;  // finite but absurd
    }
    world.step(bad);
    expect_sound(world, t);
  }
  EXPECT_EQ(world.rejected_inputs(), sent);
  world.write_snapshot(after);
  EXPECT_DOUBLE_EQ(after.insertion_m, good.insertion_m);
  EXPECT_DOUBLE_EQ(after.rotation_rad, good.rotation_rad);
  EXPECT_LT((after.tip_m - before.tip_m).norm(), 2e-3);  // held where it was
  // and the session goes on to the LAD as if nothing happened
  for (; t <= script.end_s(); t += dt) world.step(script.at(t));
  world.write_snapshot(after);
  EXPECT_EQ(world.vessel_tree().branches[after.tip_branch].name, "LAD");
}

// the pieces of the world's guidewire pipeline, so a test can put the wire where the world
// never would
struct Pipeline {
  anatomy::VesselTree tree = anatomy::make_coronary_phantom({1});
  GuidewireParams gp;
  VesselContactParams cp;
  FrictionParams fp;
  ChainMailWire wire{gp, CatheterPath(anatomy::guide_catheter_path(tree))};
  SdfLumen lumen{tree, cp.sdf_spacing_m};
  WallContact contact{cp, lumen, wire.node_count()};
  CoulombFriction friction{fp, wire.node_count()};
  void step(double insertion_m, double rotation_rad, bool with_contact = true) {
    wire.begin_step(insertion_m, rotation_rad);
    contact.begin_step();
    friction.begin_step(wire);
    for (int k = 0; k < gp.optimisation_passes; ++k) {
      wire.optimise_pass(k);
      if (!with_contact) continue;
      contact.project(wire);
      friction.apply(wire, contact);
    }
    if (with_contact) {
      wire.restore_limits(&lumen, cp.wall_margin_m);
    } else {
      wire.restore_limits();
    }
    wire.end_step();
  }
};

TEST(GuidewireHardCases, WireStartingOutsideTheLumen) {
  Pipeline p;
  // 40 mm pushed out with no walls: the straight wire leaves the LM through its wall
  for (int k = 0; k <= 40; ++k) p.step(0.001 * k, 0.0, false);
  ASSERT_GT(test::worst_wall_distance_m(p.wire, p.lumen), 1e-3);
  // walls on: within a second every node is back inside the margin, limits holding throughout
  for (int k = 0; k < 30; ++k) {
    p.step(0.040, 0.0);
    ASSERT_TRUE(sane(p.wire)) << k;
    ASSERT_EQ(check_limits(p.wire).bad_links, 0) << k;
  }
  EXPECT_LE(test::worst_wall_distance_m(p.wire, p.lumen), p.cp.wall_margin_m + 1e-9);
}

TEST(GuidewireHardCases, ZeroLengthAndFoldedSegments) {
  Pipeline p;
  for (int k = 0; k <= 30; ++k) p.step(0.001 * k, 0.0);
  const int n = p.wire.segment_count();
  const double h = p.wire.rest_length_m();
  auto x = p.wire.mutable_nodes_m();
  const Eigen::Vector3d t = (x[n - 12] - x[n - 13]).normalized();
  x[n - 14] = x[n - 15];           // a zero-length link
  x[n - 10] = x[n - 11] - h * t;   // a link folded straight back
  x[n - 5] = x[n - 6] = x[n - 4];  // three coincident nodes in the tip
  x[n] = x[n - 1] - 0.5 * h * t;   // the tip folded onto itself
  p.step(0.030, 0.0);
  ASSERT_TRUE(sane(p.wire));
  EXPECT_EQ(check_limits(p.wire).bad_links, 0);  // restored within the step
  for (int k = 0; k < 30; ++k) p.step(0.030, 0.0);
  EXPECT_TRUE(sane(p.wire));
  EXPECT_EQ(check_limits(p.wire).bad_links, 0);
  EXPECT_LE(test::worst_wall_distance_m(p.wire, p.lumen), p.cp.wall_margin_m + 1e-9);
  // the links are back near their rest length, not merely inside the limits
  const auto y = p.wire.nodes_m();
  for (int j = p.wire.first_free_node(); j < n; ++j) EXPECT_NEAR((y[j + 1] - y[j]).norm(), h, 0.05 * h) << j;
}

TEST(GuidewireHardCases, LumenQueriesFarOutsideTheSdfGrid) {
  Pipeline p;
  const Eigen::Vector3d far_points[] = {Eigen::Vector3d(1.0, 0.0, 0.0), Eigen::Vector3d(-3.0, 2.0, 50.0),
                                        Eigen::Vector3d(1e6, -1e6, 1e6), Eigen::Vector3d(0.0, 0.0, -0.3)};
  for (const auto& q : far_points) {
    const WallSample s = p.lumen.sample(q);
    EXPECT_TRUE(std::isfinite(s.distance_m)) << q.transpose();
    EXPECT_GT(s.distance_m, 0.0) << q.transpose();
    EXPECT_NEAR(s.normal.norm(), 1.0, 1e-9) << q.transpose();
  }
  const WallSample s = p.lumen.sample(Eigen::Vector3d(std::nan(""), 0.0, 0.0));
  EXPECT_TRUE(std::isfinite(s.distance_m));
  EXPECT_GT(s.distance_m, 0.0);
  // a node flung a metre away is brought back to the wall by contact within a few passes
  for (int k = 0; k <= 20; ++k) p.step(0.001 * k, 0.0);
  auto x = p.wire.mutable_nodes_m();
  x[p.wire.segment_count()] = Eigen::Vector3d(1.0, 0.5, -0.5);
  p.contact.begin_step();
  for (int k = 0; k < 4; ++k) p.contact.project(p.wire);
  EXPECT_LE(p.lumen.sample(p.wire.nodes_m().back()).distance_m, p.cp.wall_margin_m);
  p.step(0.020, 0.0);
  EXPECT_TRUE(sane(p.wire));
  EXPECT_EQ(check_limits(p.wire).bad_links, 0);
}

}  // namespace
}  // namespace pcisim::physics
