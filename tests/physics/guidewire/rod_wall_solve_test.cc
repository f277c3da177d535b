// The rod with its wall inside the solve (GuidewireParams::rod_contact kSolve, issue #33), against
// beam theory it does not compute: a clamped wire whose tip a frictionless wall pushes sideways
// presses with 3 EI D / L^3; a wire fed at an angle onto a flat wall presses with the clamped
// beam's 2 EI theta^3 / 9 d^2 and the hub holds what the wall pushes. Round a bend the
// substeps are halved where the linearised contact stops holding, and the wire comes to rest;
// pushed into a dead end the grip slips; a straight wire loaded end-on into a rounded end buckles
// at the clamped-pinned Euler load (the bench's capstan and end-on rigs: pcisim-bench wire-force,
// docs/benchmarks/wire-force.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <vector>

#include "anatomy/phantom/tube_phantoms.h"
#include "physics/guidewire/rod_wire.h"
#include "physics/guidewire/tube_lumen.h"
#include "realtime/allocation_count.h"
#include "tests/physics/guidewire/wire_test_support.h"

namespace pcisim::physics {
namespace {

constexpr double kDt = 1.0 / 30.0;

GuidewireParams solve_rod(int segments = 300) {
  GuidewireParams g;
  g.model = GuidewireModel::kRod;
  g.segment_count = segments;
  g.rod_contact = RodContactScheme::kSolve;
  return g;
}

// the free wire's length from the hub to the tip
double free_length_m(const RodWire& w) {
  double s = 0.0;
  const auto x = w.nodes_m();
  for (int i = w.first_free_node() - 1; i + 1 < w.node_count(); ++i) s += (x[i + 1] - x[i]).norm();
  return s;
}

// a clamped wire of free length L (a uniform section: no soft tip) whose tip a frictionless wall
// moves sideways by D: it presses with the cantilever's 3 EI D / L^3 (small D, Euler-Bernoulli)
TEST(RodWallSolve, AWallPushingTheTipSidewaysFeelsTheCantileversStiffness) {
  const double length_m = 0.05;
  GuidewireParams g = solve_rod();
  g.tip_length_m = 0.0;
  g.tip_angle_deg = 0.0;
  const double ei = g.bending_stiffness_nm2;
  for (const double d_m : {0.25e-3, 1e-3}) {
    test::TipWall wall;
    wall.z0_m = length_m - 0.5e-3;
    const VesselContactParams contact;
    RodWire w(g, CatheterPath({Eigen::Vector3d(0, 0, -0.2), Eigen::Vector3d(0, 0, 0)}), &wall, contact);
    for (double t = 0.0; t < 1.0; t += kDt) w.step(length_m * std::min(t / 0.5, 1.0), 0.0, kDt);
    ASSERT_NEAR(free_length_m(w), length_m, 1e-6);
    // the wall comes in over 1 s until the tip's centre sits D aside, then holds 2 s
    for (double t = 0.0; t < 3.0; t += kDt) {
      wall.wall_x_m = contact.wall_margin_m - d_m * std::min(t, 1.0);
      w.step(length_m, 0.0, kDt);
      ASSERT_TRUE(w.rod().all_finite());
    }
    double force_n = 0.0;
    for (int i = w.first_free_node(); i < w.node_count(); ++i) force_n += w.wall_force_n()[i];
    const double beam_n = 3.0 * ei * d_m / (length_m * length_m * length_m);
    std::printf("tip on a wall, D %.2f mm: %.4g N (beam %.4g N, %+.2f %%), tip x %.4f mm, residual %.2g mm\n",
                1e3 * d_m, force_n, beam_n, 100.0 * (force_n / beam_n - 1.0), 1e3 * w.nodes_m().back().x(),
                1e3 * w.contact_report().residual_m);
    EXPECT_NEAR(w.nodes_m().back().x(), -d_m, 1e-6);
    EXPECT_NEAR(force_n, beam_n, 0.01 * beam_n);  // measured -0.02 % and +0.02 %
    // and a step with its contact solved allocates nothing
    long allocations = -1;
    {
      realtime::AllocationCount count;
      w.step(length_m, 0.0, kDt);
      allocations = count.allocations();
    }
    EXPECT_GT(w.contact_report().contacts, 0);
    EXPECT_EQ(allocations, 0);
  }
}

// the catheter's exit turned 10 degrees towards a flat wall: the fed wire (a uniform section)
// bends onto the wall and comes to rest on it. The wall pushes with the beam's force; at rest the
// hub holds the wire with what the wall pushes (the forces come out of one solve: the projection
// scheme's hub never sees its wall); nothing is left inside the wall and nothing moves
TEST(RodWallSolve, AWireLeaningOnAFlatWallRestsAndTheHubHoldsWhatTheWallPushes) {
  const test::Slot slot;
  const Eigen::Vector3d exit_dir(std::sin(0.17), 0.0, std::cos(0.17));
  for (const bool friction : {false, true}) {
    std::optional<FrictionParams> mu;
    if (friction) mu = FrictionParams{};
    GuidewireParams g = solve_rod();
    g.tip_length_m = 0.0;
    g.tip_angle_deg = 0.0;
    RodWire w(g, CatheterPath({-0.2 * exit_dir, Eigen::Vector3d::Zero()}), &slot, VesselContactParams{}, mu);
    double worst_m = -1.0, most_residual_m = 0.0;
    for (double t = 0.0; t < 4.0; t += kDt) {
      w.step(0.06 * std::min(t / 2.0, 1.0), 0.0, kDt);
      ASSERT_TRUE(w.rod().all_finite()) << t;
      for (int i = w.first_free_node(); i < w.node_count(); ++i)
        worst_m = std::max(worst_m, slot.sample(w.nodes_m()[i]).distance_m);
      most_residual_m = std::max(most_residual_m, w.contact_report().residual_m);
    }
    Eigen::Vector3d wall_n = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& f : w.wall_force_vector_n()) wall_n += f;
    const Eigen::Vector3d hub_n = w.rod().hub_force_n();
    std::printf(
        "flat wall, friction %d: wall pushes (%.5f %.5f %.5f) N, hub holds (%.5f %.5f %.5f) N, %d contacts, speed "
        "%.2g m/s, worst wall %+.4f mm, largest residual %.2g mm\n",
        friction, wall_n.x(), wall_n.y(), wall_n.z(), hub_n.x(), hub_n.y(), hub_n.z(), w.contact_report().contacts,
        w.rod().max_speed_m_per_s(), 1e3 * worst_m, 1e3 * most_residual_m);
    // the beam (small slopes) clamped at slope theta, d from the wall, lying on it from where it
    // touches (s = a, where w = d, w' = 0 and no moment): w = theta s - theta s^2 / a +
    // theta s^3 / (3 a^2), so a = 3 d / theta and the wall's force is EI w''' = 2 EI theta^3 / (9 d^2)
    const double theta = 0.17, d = slot.half_m - VesselContactParams{}.wall_margin_m;
    const double beam_n = 2.0 * g.bending_stiffness_nm2 * theta * theta * theta / (9.0 * d * d);
    std::printf("the beam's wall force %.5f N: the rod's is %+.2f %% off\n", beam_n,
                100 * (std::abs(wall_n.x()) / beam_n - 1));
    EXPECT_NEAR(-wall_n.x(), beam_n, 0.02 * beam_n);  // measured -0.26 % and +0.10 %
    EXPECT_LT((wall_n - hub_n).norm(), 0.02 * wall_n.norm());
    EXPECT_LT(w.rod().max_speed_m_per_s(), 1e-3);
    EXPECT_LT(most_residual_m, 0.05e-3);  // #33: 0.05 mm; measured 0.019 mm, while the wire is fed
  }
}

// the wire in the curved tube (40 mm straight, 90 degrees of 15 mm radius, 1.5 mm lumen radius;
// friction 0.3 / 0.2), its soft tip straight, the wall inside the solve
RodWire bend_wire(const TubeLumen& lumen, int halvings = GuidewireParams{}.rod_substep_halvings) {
  FrictionParams mu;
  mu.body_static = mu.tip_static = 0.3;
  mu.body_kinetic = mu.tip_kinetic = 0.2;
  GuidewireParams g = solve_rod();
  g.tip_angle_deg = 0.0;
  g.rod_substep_halvings = halvings;
  return RodWire(g, CatheterPath({Eigen::Vector3d(0, 0, -0.2), Eigen::Vector3d(0, 0, 0)}), &lumen,
                 VesselContactParams{}, mu);
}

// The contact problem is linearised where the nodes stand after the free solve; the soft tip
// fed into the bend at 92 mm/s moves 0.38 mm along the wall within a substep of 1/240 s, half as
// much again as kRetryMotionM (0.25 mm). Such substeps are taken back and halved; as the wire settles the substeps
// lengthen again. Without the halving (rod_substep_halvings 0) the same feed stays within the wall margin too: since
// the contact solve settles its near-dependent contacts (the subspace step, one cone per contact) the linearisation
// holds nodes within microns here, where before it left them 0.05 mm and more inside and only the halving kept them
// out. (No case where the linearisation alone fails is left in this suite since: the halving's need is not shown here.)
TEST(RodWallSolve, ASubstepIsHalvedWhereANodeMovesFarAlongTheWallAndTheLengthComesBack) {
  const anatomy::VesselTree tree = test::curved_tube();
  const TubeLumen lumen(tree);
  double residual_unhalved_m = 0.0;
  for (const int halvings : {GuidewireParams{}.rod_substep_halvings, 0}) {
    RodWire w = bend_wire(lumen, halvings);
    int retried = 0, finest = 0;
    double most_residual_m = 0.0;
    long allocations = -1;
    {
      // stepping allocates nothing, substeps taken back included
      pcisim::realtime::AllocationCount count;
      for (double t = 0.0; t < 3.0; t += kDt) {
        w.step(0.055 * std::min(t / 0.6, 1.0), 0.0, kDt);
        ASSERT_TRUE(w.rod().all_finite()) << t;
        retried += w.contact_report().retried;
        finest = std::max(finest, w.contact_report().finest_halvings);
        most_residual_m = std::max(most_residual_m, w.contact_report().residual_m);
      }
      allocations = count.allocations();
    }
    std::printf(
        "halvings %d: %d substeps retried, the shortest 1/%d of the set length; largest residual %.3f mm; the last "
        "step %d substeps, speed %.2g m/s\n",
        halvings, retried, 1 << finest, 1e3 * most_residual_m, w.contact_report().substeps,
        w.rod().max_speed_m_per_s());
    EXPECT_EQ(allocations, 0);
    if (halvings > 0) {
      EXPECT_GT(retried, 0);
      EXPECT_GE(finest, 1);
      EXPECT_LE(most_residual_m, 0.05e-3);  // issue #33: 0.05 mm
      // settling, the substeps are longer again than the shortest it took
      EXPECT_LT(w.contact_report().finest_halvings, finest) << "the length comes back";
      EXPECT_EQ(w.recoveries(), 0);
    } else {
      residual_unhalved_m = most_residual_m;
    }
  }
  EXPECT_LE(residual_unhalved_m, 0.05e-3) << "without halving the linearisation alone keeps the nodes out";
}

// round the bend: fed 90 mm over 3 s the wire comes to rest round it and stays 3 s, nothing past
// the wall margin, the free wire's length kept
TEST(RodWallSolve, AWireFedRoundABendComesToRestInsideTheLumen) {
  const anatomy::VesselTree tree = test::curved_tube();
  const TubeLumen lumen(tree);
  RodWire w = bend_wire(lumen);
  double worst_m = -1.0, most_residual_m = 0.0, most_hub_n = 0.0;
  for (double t = 0.0; t < 6.0; t += kDt) {
    w.step(0.09 * std::min(t / 3.0, 1.0), 0.0, kDt);
    ASSERT_TRUE(w.rod().all_finite()) << t;
    worst_m = std::max(worst_m, test::deepest_into_margin_m(w, lumen));
    most_residual_m = std::max(most_residual_m, w.contact_report().residual_m);
    most_hub_n = std::max(most_hub_n, std::abs(w.hub_axial_force_n()));
  }
  std::printf(
      "round the bend: tip at (%.1f, %.1f) mm; worst %+.3f mm past the margin, largest residual %.3f mm; at rest %.2g "
      "m/s, crumpled %.3f mm, hub %.4f N (%.4f N at most), wall %.4f N over %d contacts\n",
      1e3 * w.nodes_m().back().x(), 1e3 * w.nodes_m().back().z(), 1e3 * worst_m, 1e3 * most_residual_m,
      w.rod().max_speed_m_per_s(), 1e3 * w.compression_m(), w.hub_axial_force_n(), most_hub_n,
      [&] {
        double n = 0;
        for (double f : w.wall_force_n()) n += f;
        return n;
      }(),
      w.contact_report().contacts);
  EXPECT_GT(w.nodes_m().back().x(), 0.02);  // round the bend
  EXPECT_EQ(w.recoveries(), 0);
  EXPECT_LT(w.rod().max_speed_m_per_s(), 1e-3);
  EXPECT_LE(most_residual_m, 0.05e-3);        // (what is left is moved out afterwards: worst is printed only)
  EXPECT_LT(w.compression_m(), 0.01 * 0.09);  // issue #33: the free wire's length kept within 1 %
  // what the hand feels of the bend: the friction that held the wire back as it was fed, a few
  // hundredths of a newton (0.3 of the bend's wall force), never the projection scheme's nothing
  EXPECT_GT(most_hub_n, 0.005);
  EXPECT_LT(most_hub_n, 0.2);
}

// round the bend, then a minute at rest (issue #33: energy must not grow): held 60 s the wire
// comes to rest and stays there, nothing deeper in the wall than 0.05 mm, its length kept. The
// contact solve's tolerance sets how still: its sweeps stop once no update moves a node more than
// kContactToleranceM, and what is left unresolved is a speed over the substep (measured: 1e-7 m,
// the wire buzzed at 2.4e-5 m/s, 1e-16-1e-13 J, the hub 0.008-0.020 N step to step; 1e-10 m,
// 7.6e-23 J)
TEST(RodWallSolve, AWireRoundABendRestsForAMinuteWithoutGainingEnergy) {
  const anatomy::VesselTree tree = test::curved_tube();
  const TubeLumen lumen(tree);
  RodWire w = bend_wire(lumen);
  test::expect_round_a_bend_and_a_minute_at_rest(w, lumen, kDt);
}

// a wide straight tube carried sideways at a constant 0.1 m/s, the blood with it: nothing in
// the physics knows the frame, so the free wire (its soft tip ten times heavier for its motion)
// stays as straight as in a still tube. The blood's drag is passed back relative to the wall at
// each node's own rate: at one rate for all, the heavier tip was pushed ahead by 9 m c v
struct GlidingTube final : LumenMotion {
  double t_s = 0.0;
  static constexpr double kSpeedMPerS = 0.1;
  Eigen::Vector3d displacement_m(const Eigen::Vector3d&, double a) const override {
    return Eigen::Vector3d(0.0, kSpeedMPerS * (t_s + a * kDt), 0.0);
  }
};

TEST(RodWallSolve, InATubeGlidingSidewaysTheWireIsAsInAStillOne) {
  std::vector<Eigen::Vector3d> centerline;
  for (double z = -2e-3; z <= 0.1; z += 0.5e-3) centerline.push_back({0.0, 0.0, z});
  const anatomy::VesselTree tree = anatomy::tube_through(centerline, 3e-3);
  const TubeLumen lumen(tree);
  GuidewireParams g = solve_rod(200);
  g.tip_angle_deg = 0.0;
  RodWire w(g, CatheterPath({Eigen::Vector3d(0, 0, -0.2), Eigen::Vector3d(0, 0, 0)}), &lumen, VesselContactParams{});
  w.set_gravity_m_per_s2(Eigen::Vector3d::Zero());
  GlidingTube tube;
  w.set_lumen_motion(&tube);
  // the wire starts at rest while the tube is already gliding: a transient (measured 3 um off),
  // then, over the second second, on the axis (1.4e-11 m, still falling; 0.19 mm at one rate)
  double transient_m = 0.0, settled_m = 0.0;
  for (int k = 0; k < 60; ++k, tube.t_s += kDt) {
    w.step(0.05, 0.0, kDt);
    ASSERT_TRUE(w.rod().all_finite()) << k;
    const double shift_m = GlidingTube::kSpeedMPerS * (tube.t_s + kDt);
    double off_m = 0.0;  // in the tube's frame every node lies on its axis
    for (int i = w.first_free_node(); i < w.node_count(); ++i)
      off_m = std::max(off_m, (w.nodes_m()[i] - Eigen::Vector3d(0.0, shift_m, 0.0)).head<2>().norm());
    (k < 30 ? transient_m : settled_m) = std::max(k < 30 ? transient_m : settled_m, off_m);
  }
  std::printf(
      "gliding tube (0.1 m/s): the free wire off the tube's axis by %.3g mm at most in the first second, %.3g "
      "mm in the second\n",
      1e3 * transient_m, 1e3 * settled_m);
  EXPECT_EQ(w.recoveries(), 0);
  EXPECT_LT(transient_m, 0.02e-3);
  EXPECT_LT(settled_m, 1e-9);
}

// a dead end: the tube closes 124 mm along its centerline; fed on from 110 mm towards 150 mm. The
// hub's force rises until the grip slips at 1 N and stays bounded, the tip presses the end, and
// the wire keeps its length within issue #33's 1 % (1.24 mm; 0.06 mm measured since the last
// substep's wall force is in the prediction: 2.66 mm as the tip met the end before)
TEST(RodWallSolve, PushedIntoADeadEndTheWireKeepsItsLengthAndTheGripSlips) {
  const anatomy::VesselTree tree = test::curved_tube();
  const TubeLumen lumen(tree);
  RodWire w = bend_wire(lumen);
  for (double t = 0.0; t < 3.5; t += kDt) w.step(0.11 * std::min(t / 3.0, 1.0), 0.0, kDt);
  double worst_m = -1.0, most_crumpled_m = 0.0, most_hub_n = 0.0, most_jump_n = 0.0, most_tip_n = 0.0;
  double last_hub_n = w.hub_axial_force_n();
  for (double t = 0.0; t < 1.5; t += kDt) {
    w.step(0.11 + 0.04 * std::min(t / 1.0, 1.0), 0.0, kDt);
    ASSERT_TRUE(w.rod().all_finite()) << t;
    worst_m = std::max(worst_m, test::deepest_into_margin_m(w, lumen));
    most_crumpled_m = std::max(most_crumpled_m, w.compression_m());
    most_hub_n = std::max(most_hub_n, w.hub_axial_force_n());
    most_tip_n = std::max(most_tip_n, w.tip_contact_force_n());
    most_jump_n = std::max(most_jump_n, std::abs(w.hub_axial_force_n() - last_hub_n));
    last_hub_n = w.hub_axial_force_n();
  }
  std::printf(
      "dead end: fed %.1f of %.1f mm; hub %.3f N at most (largest step change %.3f N), tip %.3f N at most; crumpled "
      "%.3f mm at most, worst %+.3f mm past the margin\n",
      1e3 * w.fed_length_m(), 1e3 * w.commanded_feed_m(), most_hub_n, most_jump_n, most_tip_n, 1e3 * most_crumpled_m,
      1e3 * worst_m);
  EXPECT_EQ(w.recoveries(), 0);
  EXPECT_LT(most_crumpled_m, 0.01 * 0.124);
  EXPECT_GT(w.refused_feed_m(), 0.01) << "the grip slipped";
  EXPECT_GT(most_hub_n, GuidewireParams{}.feed_refuse_force_n);
  EXPECT_LT(most_hub_n, 3.0 * GuidewireParams{}.feed_refuse_force_n);
  EXPECT_GT(most_tip_n, 0.1) << "the tip presses the end";
}

// Euler (Timoshenko & Gere 2.6): a column clamped at one end and pinned at the other first buckles
// at x1^2 EI / L^2, x1 = 4.4934 the first root of tan x = x. A straight wire (no soft tip, no
// friction) fed to the rounded end of a straight tube of 0.5 mm clearance, then loaded: the hub's
// force raised by 0.02 EI / L^2 a step, the feed moved by half the column's axial compliance times
// the shortfall (a rigid push overshoots: 1 um of feed is 0.2 N here). Before the last substep's
// wall force went into the prediction and the wall's curvature into the contact problem, the tip
// slid off the end's pole within a step and the wire shortened instead of bowing
TEST(RodWallSolve, AStraightWireLoadedEndOnBucklesAtEulersLoad) {
  const VesselContactParams contact;
  const double length_m = 0.03, clearance_m = 0.5e-3;
  std::vector<Eigen::Vector3d> centerline;
  for (double z = -2e-3; z < length_m - clearance_m; z += 0.5e-3) centerline.push_back({0.0, 0.0, z});
  centerline.push_back({0.0, 0.0, length_m - clearance_m});  // the cap's pole, less the margin, at L
  const anatomy::VesselTree tree = anatomy::tube_through(centerline, clearance_m + contact.wall_margin_m);
  const TubeLumen lumen(tree);
  GuidewireParams g = solve_rod();
  g.tip_length_m = 0.0;
  g.tip_angle_deg = 0.0;
  g.feed_refuse_force_n = 100.0;
  RodWire w(g, CatheterPath({Eigen::Vector3d(0, 0, -0.2), Eigen::Vector3d(0, 0, 0)}), &lumen, contact);
  w.set_gravity_m_per_s2(Eigen::Vector3d(0.05, 0.0, 0.0));  // the imperfection
  double fed_m = 0.0;
  auto lateral_m = [&] {
    double most = 0.0;
    for (int i = w.first_free_node(); i < w.node_count(); ++i) most = std::max(most, w.nodes_m()[i].head<2>().norm());
    return most;
  };
  // fed until its tip meets the end (the last millimetre at 5 mm/s)
  while (fed_m < length_m) {
    fed_m = std::min(fed_m + (fed_m < length_m - 1e-3 ? 1.5e-3 : 0.167e-3), length_m);
    w.step(fed_m, 0.0, kDt);
  }
  const double ei = g.bending_stiffness_nm2, rate_n = 0.02 * ei / (length_m * length_m);
  double target_n = std::max(w.hub_axial_force_n(), 0.0), buckling_n = 0.0;
  for (int k = 0; k < 2000 && buckling_n == 0.0; ++k) {
    target_n += rate_n;
    fed_m += 0.5 * length_m / kWireAxialStiffnessN * (target_n - w.hub_axial_force_n());
    w.step(fed_m, 0.0, kDt);
    ASSERT_TRUE(w.rod().all_finite()) << k;
    if (lateral_m() >= 0.5 * clearance_m) buckling_n = w.hub_axial_force_n();
  }
  // the column: from the hub node (the rod's clamp) to the end's stop
  const double column_m = length_m - w.nodes_m()[w.first_free_node() - 1].z();
  const double x1 = 4.493409457909064, euler_n = x1 * x1 * ei / (column_m * column_m);
  std::printf("end on: buckled at %.5f N (Euler, clamped-pinned over %.3f mm: %.5f N, %+.2f %%), crumpled %.4f mm\n",
              buckling_n, 1e3 * column_m, euler_n, 100.0 * (buckling_n / euler_n - 1.0), 1e3 * w.compression_m());
  EXPECT_NEAR(buckling_n, euler_n, 0.03 * euler_n);  // issue #33's 3 %
  EXPECT_EQ(w.recoveries(), 0);                      // (a recovery lays the wire out straight)
  EXPECT_LT(w.compression_m(), 0.01 * length_m);
  // then pushed 3 mm further at 5 mm/s: the bowed wire meets the side wall and the end's rounded
  // cap at once. Until session 32 every such push blew up within a millimetre (the last
  // substep's force, in the prediction, carried the light tip millimetres from the cap, and the
  // contact was posed on the wall there); it must stay in the tube, keep its length and push back
  // with a bounded force
  double most_hub_n = 0.0, worst_m = -1.0, most_crumpled_m = 0.0, least_tip_z_m = length_m;
  const double more_from_m = fed_m;
  while (fed_m < more_from_m + 3e-3) {
    fed_m += 0.167e-3;
    w.step(fed_m, 0.0, kDt);
    ASSERT_TRUE(w.rod().all_finite());
    most_hub_n = std::max(most_hub_n, w.hub_axial_force_n());
    most_crumpled_m = std::max(most_crumpled_m, w.compression_m());
    least_tip_z_m = std::min(least_tip_z_m, w.nodes_m().back().z());
    for (int i = w.first_free_node(); i < w.node_count(); ++i)
      worst_m = std::max(worst_m, lumen.sample(w.nodes_m()[i]).distance_m + contact.wall_margin_m);
  }
  std::printf(
      "end on, 3 mm after the buckle: hub %.3f N at most, crumpled %.4f mm, worst %+.4f mm past the margin, "
      "the tip %.3f mm from the end at most\n",
      most_hub_n, 1e3 * most_crumpled_m, 1e3 * worst_m, 1e3 * (length_m - clearance_m - least_tip_z_m));
  EXPECT_EQ(w.recoveries(), 0);
  EXPECT_LT(worst_m, 0.05e-3);                  // issue #33's penetration
  EXPECT_LT(most_crumpled_m, 0.01 * length_m);  // the free wire's length, within 1 %
  // the tip stays in the column's far half (the bench's test; it does leave the end's cap: 2.6 mm
  // back at most in session 32's run, a defect not traced)
  EXPECT_GT(least_tip_z_m, 0.5 * length_m);
  EXPECT_LT(most_hub_n, 50.0);  // bounded: the bench calls more a blow-up
}

}  // namespace
}  // namespace pcisim::physics
