// The debrief's figures (server/debrief/session_metrics.h) on scripted sessions whose truth is
// known independently: a tip moved along a circle (the chord sum of a regular polygon), along
// and across the beam, through a tree with a target branch, pressed with a scripted force; the
// beam's pulses with the inverse-square dose worked out here by hand.
#include "server/debrief/session_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "anatomy/vessel/vessel_tree.h"
#include "realtime/allocation_count.h"

namespace pcisim::server {
namespace {

constexpr int64_t kSecond = 1'000'000'000;

// aorta <- LM <- {LAD <- D1, LCx}
anatomy::VesselTree small_tree() {
  anatomy::VesselTree t;
  const auto branch = [&](const char* name, int parent) {
    anatomy::VesselBranch b;
    b.name = name;
    b.parent = parent;
    t.branches.push_back(b);
  };
  branch("aorta", -1);
  branch("LM", 0);
  branch("LAD", 1);
  branch("LCx", 1);
  branch("D1", 2);
  return t;
}

physics::WorldSnapshot state(int64_t step, double time_s, const Eigen::Vector3d& tip_mm, int branch = -1,
                             double tip_force_n = 0.0) {
  physics::WorldSnapshot s;
  s.step = step;
  s.time_s = time_s;
  s.wire_nodes_m.assign(2, Eigen::Vector3d::Zero());
  s.tip_m = tip_mm * 1e-3;
  s.tip_rest_m = s.tip_m;  // (still vessels unless a test moves them)
  s.tip_branch = branch;
  s.tip_force_n = tip_force_n;
  return s;
}

DebriefParams with_target(const char* target) {
  DebriefParams p;
  p.target_branch = target;
  return p;
}

TEST(SessionMetrics, TheTipsPathIsTheChordSumAndItsProjectionAcrossTheBeam) {
  SessionMetrics m;
  int64_t step = 0;
  // the next state, 30 a second
  const auto next = [&step](const Eigen::Vector3d& tip_mm) {
    const int64_t k = step++;
    return state(k, k / 30.0, tip_mm);
  };
  m.begin_pipeline(DebriefParams{}, small_tree(), false, BeamGeometry{}, kSecond);
  // a circle of 5 mm radius in the x-z plane, 240 states a turn, seen in AP (the beam along -y):
  // the path is the regular polygon's perimeter, 2 n r sin(pi / n), and lies across the beam
  const int n = 240;
  const double r_mm = 5.0;
  for (int k = 0; k <= n; ++k) {
    const double a = 2.0 * std::numbers::pi * k / n;
    m.record_wire(next(Eigen::Vector3d(r_mm * std::cos(a), 0.0, r_mm * std::sin(a))), 0, 0, kSecond);
  }
  const double polygon_mm = 2.0 * n * r_mm * std::sin(std::numbers::pi / n);
  DebriefFigures f = m.figures(2 * kSecond);
  EXPECT_NEAR(f.tip_path_mm, polygon_mm, 1e-9);
  EXPECT_NEAR(f.tip_path_projected_mm, polygon_mm, 1e-9);
  // then 10 mm along the beam: the path grows by 10, its projection not at all
  m.record_wire(next(Eigen::Vector3d(r_mm, -10.0, 0.0)), 0, 0, kSecond);
  f = m.figures(2 * kSecond);
  EXPECT_NEAR(f.tip_path_mm, polygon_mm + 10.0, 1e-9);
  EXPECT_NEAR(f.tip_path_projected_mm, polygon_mm, 1e-9);
  // at LAO 90 the beam runs along +x: a move along x is along the beam
  m.record_wire(next(Eigen::Vector3d(r_mm + 4.0, -10.0, 0.0)), 90, 0, kSecond);
  f = m.figures(2 * kSecond);
  EXPECT_NEAR(f.tip_path_mm, polygon_mm + 14.0, 1e-9);
  EXPECT_NEAR(f.tip_path_projected_mm, polygon_mm, 1e-9);
  EXPECT_EQ(f.wire_states, n + 3);
  EXPECT_EQ(f.resets, 0);
  EXPECT_NEAR(f.tip_path_in_vessels_mm, f.tip_path_mm, 1e-9);
}

TEST(SessionMetrics, TheBeatCarriesTheTipButItsPathThroughTheVesselsIsTheSteeredOne) {
  SessionMetrics m;
  m.begin_pipeline(DebriefParams{}, small_tree(), false, BeamGeometry{}, kSecond);
  // the wire fed 10 mm along z over 3 s (30 states a second) while the heart carries the tip
  // 4 mm to and fro along x once a second: 10 mm steered, 3 beats x 8 mm carried on top
  for (int k = 0; k <= 90; ++k) {
    physics::WorldSnapshot s = state(k, k / 30.0, Eigen::Vector3d::Zero());
    s.tip_rest_m = Eigen::Vector3d(0, 0, 10e-3 * k / 90.0);
    const double beat_mm = 2.0 - 2.0 * std::cos(2.0 * std::numbers::pi * k / 30.0);
    s.tip_m = s.tip_rest_m + Eigen::Vector3d(beat_mm * 1e-3, 0, 0);
    m.record_wire(s, 0, 0, kSecond);
  }
  const DebriefFigures f = m.figures(5 * kSecond);
  EXPECT_NEAR(f.tip_path_in_vessels_mm, 10.0, 1e-9);
  EXPECT_GT(f.tip_path_mm, 3 * 8.0) << "the beat's to and fro counts in the world";
  EXPECT_LT(f.tip_path_mm, 3 * 8.0 + 10.0);
}

TEST(SessionMetrics, AWireThatStartsOverIsNotJoinedToItsLastPath) {
  SessionMetrics m;
  m.begin_pipeline(DebriefParams{}, small_tree(), false, BeamGeometry{}, kSecond);
  m.record_wire(state(10, 1.0, Eigen::Vector3d(0, 0, 0)), 0, 0, kSecond);
  m.record_wire(state(11, 1.1, Eigen::Vector3d(3, 0, 0)), 0, 0, kSecond);
  // a reset: the step count starts again, the tip is back at the start 40 mm away
  m.record_wire(state(1, 0.03, Eigen::Vector3d(43, 0, 0)), 0, 0, 2 * kSecond);
  m.record_wire(state(2, 0.06, Eigen::Vector3d(45, 0, 0)), 0, 0, 2 * kSecond);
  // a new scene: its first state is not joined either
  m.begin_pipeline(DebriefParams{}, small_tree(), false, BeamGeometry{}, 3 * kSecond);
  m.record_wire(state(5, 0.2, Eigen::Vector3d(-100, 0, 0)), 0, 0, 3 * kSecond);
  m.record_wire(state(6, 0.23, Eigen::Vector3d(-99, 0, 0)), 0, 0, 3 * kSecond);
  const DebriefFigures f = m.figures(4 * kSecond);
  EXPECT_NEAR(f.tip_path_mm, 3.0 + 2.0 + 1.0, 1e-12);
  EXPECT_EQ(f.resets, 2);
  EXPECT_DOUBLE_EQ(f.procedure_time_s, 3.0) << "from the first scene's start";
}

TEST(SessionMetrics, TimeInAWrongBranchIsTimeOffTheRouteToTheTarget) {
  SessionMetrics m;
  const anatomy::VesselTree tree = small_tree();
  m.begin_pipeline(with_target("LAD"), tree, false, BeamGeometry{}, kSecond);
  // the tip's branches, each held for its time (s): the route is aorta, LM, LAD
  const std::vector<std::pair<const char*, double>> visit = {{"aorta", 1.0}, {"LM", 1.0}, {"LCx", 2.0}, {"LM", 0.5},
                                                             {"LAD", 1.0},   {"D1", 1.5}, {"LAD", 0.7}};
  double t = 0.0, wrong = 0.0;
  int64_t step = 0;
  const double dt = 0.1;
  for (const auto& [name, seconds] : visit) {
    const int b = tree.find(name);
    const std::string n = name;
    if (n == "LCx" || n == "D1") wrong += seconds;
    for (int k = 0; k < static_cast<int>(std::lround(seconds / dt)); ++k, t += dt)
      m.record_wire(state(step++, t, Eigen::Vector3d::Zero(), b), 0, 0, kSecond + static_cast<int64_t>(t * 1e9));
  }
  m.record_wire(state(step++, t, Eigen::Vector3d::Zero(), tree.find("LAD")), 0, 0, kSecond);
  const DebriefFigures f = m.figures(20 * kSecond);
  ASSERT_TRUE(f.has_target);
  EXPECT_NEAR(f.wrong_branch_s, wrong, 1e-9);
  // first in the LAD after aorta, LM, LCx and LM again: 4.5 s in (the session began at 1 s)
  EXPECT_NEAR(f.target_reached_s, 4.5, 1e-6);
  const nlohmann::json j = to_json(f);
  EXPECT_NEAR(j.at("wrong_branch_s").get<double>(), 3.5, 1e-9);
  EXPECT_EQ(j.at("target_branch"), "LAD");

  // a target the tree does not have, or none: no wrong-branch figure rather than a zero
  SessionMetrics none;
  none.begin_pipeline(with_target("OM9"), tree, false, BeamGeometry{}, kSecond);
  none.record_wire(state(0, 0.0, Eigen::Vector3d::Zero(), tree.find("LCx")), 0, 0, kSecond);
  none.record_wire(state(1, 1.0, Eigen::Vector3d::Zero(), tree.find("LCx")), 0, 0, kSecond);
  EXPECT_TRUE(to_json(none.figures(2 * kSecond)).at("wrong_branch_s").is_null());
}

TEST(SessionMetrics, ForceEpisodesAboveTheRiskForceAndTimeAboveTheThreshold) {
  DebriefParams p;
  p.tip_force_threshold_n = 0.05;
  p.tip_force_risk_n = 0.12;
  SessionMetrics m;
  m.begin_pipeline(p, small_tree(), true, BeamGeometry{}, kSecond);
  // 30 Hz states: 0.02 N, then 0.08 N for 1 s, 0.2 N for 0.5 s (peak 0.31 N inside), 0.02 N,
  // 0.15 N for 0.2 s, 0.0 N: two episodes above 0.12 N; 1.7 s above 0.05 N
  std::vector<double> force;
  const auto hold = [&](double n, double seconds) {
    for (int k = 0; k < static_cast<int>(std::lround(seconds * 30)); ++k) force.push_back(n);
  };
  hold(0.02, 1.0);
  hold(0.08, 1.0);
  hold(0.2, 0.5);
  force[force.size() - 5] = 0.31;
  hold(0.02, 1.0);
  hold(0.15, 0.2);
  hold(0.0, 1.0);
  for (size_t k = 0; k < force.size(); ++k)
    m.record_wire(state(static_cast<int64_t>(k), k / 30.0, Eigen::Vector3d::Zero(), 0, force[k]), 0, 0,
                  kSecond + static_cast<int64_t>(k * 1e9 / 30));
  const DebriefFigures f = m.figures(10 * kSecond);
  EXPECT_TRUE(f.tip_forces_known);
  EXPECT_DOUBLE_EQ(f.peak_tip_force_n, 0.31);
  EXPECT_EQ(f.force_events, 2);
  EXPECT_NEAR(f.tip_force_above_threshold_s, 1.7, 1e-9);
  int listed = 0;
  for (const TimelineEntry& e : f.timeline) {
    if (e.kind != TimelineKind::kForceEvent) continue;
    ++listed;
    EXPECT_NEAR(e.b, listed == 1 ? 0.5 : 0.2, 1e-9) << "its duration";
    EXPECT_DOUBLE_EQ(e.a, listed == 1 ? 0.31 : 0.15) << "its peak";
    EXPECT_NEAR(e.time_s, listed == 1 ? 2.0 : 3.5, 1e-6) << "when it began";
  }
  EXPECT_EQ(listed, 2);

  // the chain-mail computes no wall force: no force figures rather than zeros
  SessionMetrics chain;
  chain.begin_pipeline(p, small_tree(), false, BeamGeometry{}, kSecond);
  chain.record_wire(state(0, 0.0, Eigen::Vector3d::Zero(), 0, 0.0), 0, 0, kSecond);
  const nlohmann::json j = to_json(chain.figures(2 * kSecond));
  for (const char* key : {"peak_tip_force_n", "force_events", "tip_force_above_threshold_s"})
    EXPECT_TRUE(j.at(key).is_null()) << key;
}

// a 60 mm wire along +x at 1 mm nodes whose last `bent_mm` turn round a circle of radius 1.5 mm by
// `turn_deg` (180: folded back along itself)
std::vector<Eigen::Vector3d> wire_with_tip_turned(double turn_deg, double bent_mm) {
  std::vector<Eigen::Vector3d> nodes;
  const double r = 1.5e-3, straight = 60e-3 - bent_mm * 1e-3;
  for (double a = 0.0; a <= 60e-3 + 1e-9; a += 1e-3) {
    if (a <= straight) {
      nodes.emplace_back(a, 0.0, 0.0);
      continue;
    }
    // round the circle until turned, then straight on
    const double arc = a - straight, turn = turn_deg * std::numbers::pi / 180.0, on_arc = std::min(arc, r * turn);
    const double phi = on_arc / r;
    Eigen::Vector3d p(straight + r * std::sin(phi), r * (1.0 - std::cos(phi)), 0.0);
    p += (arc - on_arc) * Eigen::Vector3d(std::cos(turn), std::sin(turn), 0.0);
    nodes.push_back(p);
  }
  return nodes;
}

TEST(SessionMetrics, AWireFoldedBackIsAProlapseATurnIntoABranchIsNot) {
  SessionMetrics m;
  m.begin_pipeline(DebriefParams{}, small_tree(), false, BeamGeometry{}, kSecond);
  int64_t k = 0;
  const auto hold = [&](const std::vector<Eigen::Vector3d>& nodes, int states) {
    for (int i = 0; i < states; ++i, ++k) {
      physics::WorldSnapshot s = state(k, k / 30.0, nodes.back() * 1e3);
      s.wire_nodes_m = nodes;
      m.record_wire(s, 0, 0, kSecond + k * kSecond / 30);
    }
  };
  hold(wire_with_tip_turned(0, 10), 10);
  hold(wire_with_tip_turned(90, 10), 20);   // the tip taken into a side branch at a right angle
  hold(wire_with_tip_turned(180, 12), 15);  // folded back: the last 5 mm run along -x
  hold(wire_with_tip_turned(0, 10), 10);
  const DebriefFigures f = m.figures(5 * kSecond);
  EXPECT_EQ(f.prolapse_events, 1);
  int listed = 0;
  for (const TimelineEntry& e : f.timeline) {
    if (e.kind != TimelineKind::kProlapse) continue;
    ++listed;
    EXPECT_GT(e.a, 170.0) << "the fold (the point 10 mm back lies on the bend: a little short of 180)";
    EXPECT_NEAR(e.b, 15 / 30.0, 1e-9) << "its duration";
    EXPECT_NEAR(e.time_s, 30 / 30.0, 1e-6) << "from the first folded state";
  }
  EXPECT_EQ(listed, 1);
}

TEST(SessionMetrics, FeedTheTipDoesNotTakeUpIsBuckling) {
  // fed 10 mm/s for 3 s; the tip follows but for a second in the middle, when it holds still; at
  // 30 and at 120 states a second (the window is a second of sim time, whatever the physics rate)
  for (const int hz : {30, 120})
    for (const bool stuck : {false, true}) {
      SCOPED_TRACE(hz);
      SessionMetrics m;
      m.begin_pipeline(DebriefParams{}, small_tree(), false, BeamGeometry{}, kSecond);
      for (int k = 0; k <= 3 * hz; ++k) {
        const double t = static_cast<double>(k) / hz, fed_mm = 10.0 * t;
        const double tip_mm = !stuck ? fed_mm : t < 1.0 ? fed_mm : t < 2.0 ? 10.0 : fed_mm - 10.0;
        physics::WorldSnapshot s = state(k, t, Eigen::Vector3d(tip_mm, 0, 0));
        s.insertion_m = fed_mm * 1e-3;
        m.record_wire(s, 0, 0, kSecond + k * kSecond / hz);
      }
      const DebriefFigures f = m.figures(5 * kSecond);
      if (!stuck) {
        EXPECT_EQ(f.buckling_events, 0) << "the tip takes up the feed";
        continue;
      }
      // over a second's window the tip moves under a quarter of the 10 mm fed from t = 1.75 s (it
      // stopped at 1 s) until 2.25 s (it moved on at 2 s): one episode of half a second
      EXPECT_EQ(f.buckling_events, 1);
      for (const TimelineEntry& e : f.timeline) {
        if (e.kind != TimelineKind::kBuckling) continue;
        EXPECT_NEAR(e.b, 0.5, 2.0 / 30) << "its duration (the ring keeps a sample every 1/32 s at most)";
        EXPECT_NEAR(e.a, 10.0, 1e-6) << "at most the whole second's feed not taken up";
      }
    }
}

TEST(SessionMetrics, TheBeamsTimeCineRunsAndDoseAtTheReferencePoint) {
  DebriefParams p;  // 50 uGy/mAs at 1 m, 0.15 mAs a fluoroscopy pulse, 1.5 mAs a cine frame
  SessionMetrics m;
  // the default scene's C-arm: SAD 750 mm, SID 1100 mm, a 512 x 0.4 mm detector
  const BeamGeometry beam = beam_geometry(750, 1100, 204.8, 204.8);
  EXPECT_DOUBLE_EQ(beam.source_to_irp_mm, 600.0);
  // the detector's 20.48 cm square carried back to 60 of its 110 cm from the focal spot
  EXPECT_NEAR(beam.field_area_at_irp_cm2, 20.48 * 20.48 * (60.0 / 110.0) * (60.0 / 110.0), 1e-9);
  m.begin_pipeline(p, small_tree(), false, beam, kSecond);
  // three cine runs between fluoroscopy: the pedals as the x-ray thread sees them each tick
  const std::vector<std::pair<bool, bool>> pedals = {{false, false}, {true, false}, {true, true},   {false, true},
                                                     {false, false}, {false, true}, {false, false}, {true, true},
                                                     {true, false},  {false, false}};
  for (size_t k = 0; k < pedals.size(); ++k)
    m.record_pedals(pedals[k].first, pedals[k].second, kSecond + static_cast<int64_t>(k) * kSecond / 10);
  for (int k = 0; k < 150; ++k) m.record_pulse(false);
  for (int k = 0; k < 60; ++k) m.record_pulse(true);
  m.record_beam_time(10.0, false, -30, 30);
  m.record_beam_time(2.0, true, -30, 30);
  m.record_beam_time(1.5, false, 40, 25.2);
  m.record_beam_time(0.25, false, -30.2, 30.1);  // the same pose, within half a degree
  const DebriefFigures f = m.figures(30 * kSecond);
  EXPECT_EQ(f.cine_runs, 3);
  EXPECT_DOUBLE_EQ(f.fluoro_time_s, 13.75);
  EXPECT_DOUBLE_EQ(f.cine_time_s, 2.0);
  EXPECT_EQ(f.fluoro_pulses, 150);
  EXPECT_EQ(f.cine_frames, 60);
  // K = 50 uGy/mAs * mAs / 0.6^2 a pulse: 20.833 uGy a fluoroscopy pulse, 208.33 a cine frame
  const double kerma_mgy = (150 * 50 * 0.15 + 60 * 50 * 1.5) / 0.36 * 1e-3;
  EXPECT_NEAR(f.air_kerma_mgy, kerma_mgy, 1e-12);
  EXPECT_NEAR(f.dap_gycm2, kerma_mgy * 1e-3 * beam.field_area_at_irp_cm2, 1e-12);
  ASSERT_EQ(f.carm_poses.size(), 2u);
  EXPECT_DOUBLE_EQ(f.carm_poses[0].beam_s, 12.25);
  EXPECT_DOUBLE_EQ(f.carm_poses[1].beam_s, 1.5);
  // the timeline in order: fluoro on, cine on, fluoro off, cine off, cine on, cine off, both on, ...
  int cine_on = 0, fluoro_on = 0;
  for (const TimelineEntry& e : f.timeline) {
    cine_on += e.kind == TimelineKind::kCineOn;
    fluoro_on += e.kind == TimelineKind::kFluoroOn;
  }
  EXPECT_EQ(cine_on, 3);
  EXPECT_EQ(fluoro_on, 2);
  for (size_t k = 1; k < f.timeline.size(); ++k) EXPECT_LE(f.timeline[k - 1].time_s, f.timeline[k].time_s);
}

TEST(SessionMetrics, RecordingAllocatesNothingAndALongSessionKeepsItsFigures) {
  SessionMetrics m;
  m.begin_pipeline(with_target("LAD"), small_tree(), true, beam_geometry(750, 1100, 204.8, 204.8), kSecond, 64, 64);
  physics::WorldSnapshot s = state(0, 0.0, Eigen::Vector3d::Zero(), 2, 0.0);
  s.wire_nodes_m = wire_with_tip_turned(30, 10);  // long enough for the fold rule to walk it
  const std::vector<uint16_t> frame(64 * 64, 1000);
  {
    realtime::AllocationCount count;
    // more events than the timeline holds: force episodes every other state, pedals, injections
    for (int k = 0; k < 3 * SessionMetrics::kMaxTimeline; ++k) {
      s.step = k;
      s.time_s = k / 30.0;
      s.tip_m = Eigen::Vector3d(k * 1e-4, 0, 0);
      s.tip_force_n = k % 2 ? 0.5 : 0.0;
      s.insertion_m = 1e-3 * k;  // fed faster than the tip moves: the feed rule's window runs too
      m.record_wire(s, 0, 0, kSecond + k);
      m.record_pedals(k % 3 == 0, false, kSecond + k);
      m.record_pulse(false);
      m.record_beam_time(1.0 / 30, false, 0, 0);
      m.record_frame(frame.data(), 64, 64, xray::DetectorGeometry{}, 0.5, 1 + k % 3, kSecond + k);
      if (k % 100 == 0) m.record_carm(k % 90, 10, kSecond + k);
    }
    m.record_injection(8.0, 2 * kSecond);
    EXPECT_EQ(count.allocations(), 0);
  }
  const DebriefFigures f = m.figures(3 * kSecond);
  EXPECT_EQ(f.timeline.size(), static_cast<size_t>(SessionMetrics::kMaxTimeline));
  EXPECT_GT(f.timeline_dropped, 0);
  EXPECT_EQ(f.force_events, 3 * SessionMetrics::kMaxTimeline / 2) << "counted though not listed";
  EXPECT_NEAR(f.tip_path_mm, (3 * SessionMetrics::kMaxTimeline - 1) * 0.1, 1e-6);
  EXPECT_EQ(f.contrast_injections, 1);
  EXPECT_DOUBLE_EQ(f.contrast_ml, 8.0);
}

}  // namespace
}  // namespace pcisim::server
