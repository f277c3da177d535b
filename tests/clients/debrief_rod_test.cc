// Issue #35's check of the force figures against the wire state log: the built-in trainee played
// headless through scenes/rod.json (the rod wire computes the wall's force on its tip), each wire
// state kept as a log; the debrief's peak force, time above the threshold and force events agree
// with the log's, counted here apart from the recorder.
#include <gtest/gtest.h>

#include "anatomy/phantom/coronary_phantom.h"
#include "clients/bridge/trainee_script.h"
#include "physics/world.h"
#include "server/debrief/session_metrics.h"
#include "server/scene/scene.h"

namespace pcisim::server {
namespace {

TEST(DebriefRod, TheForceFiguresAgreeWithTheWireStateLog) {
  const Scene scene = load_scene_file(PCISIM_SOURCE_DIR "/scenes/rod.json");
  const clients::TraineeScript script = clients::TraineeScript::parse(clients::TraineeScript::builtin_text(), "b");
  physics::World world(scene.world);
  const anatomy::VesselTree tree =
      anatomy::make_coronary_phantom(anatomy::CoronaryPhantomSpec{scene.world.anatomy.seed});
  DebriefParams p = scene.debrief;
  // thresholds low enough for the built-in approach to cross them (its tip presses with mN)
  p.tip_force_threshold_n = 0.001;
  p.tip_force_risk_n = 0.003;
  SessionMetrics m;
  const int64_t t0 = 1'000'000'000;
  m.begin_pipeline(p, tree, true, BeamGeometry{}, t0);
  std::vector<std::pair<double, double>> log;  // (sim time, tip force) of each state
  physics::WorldSnapshot s;
  for (int k = 0; k * scene.world.step_s <= script.duration_s(); ++k) {
    const clients::InstrumentReading r = script.sample(k * scene.world.step_s);
    physics::InstrumentInput in;
    in.insertion_m = r.insertion_mm * 1e-3;
    in.rotation_rad = r.rotation_rad;
    world.step(in);
    world.write_snapshot(s);
    m.record_wire(s, 0, 0, t0 + static_cast<int64_t>(s.time_s * 1e9));
    log.emplace_back(s.time_s, s.tip_force_n);
  }
  // the log's own figures: the largest force; the time each state held above the threshold until
  // the next; the runs of states above the risk force
  double peak = 0.0, above_s = 0.0;
  int runs = 0;
  for (size_t k = 0; k < log.size(); ++k) {
    peak = std::max(peak, log[k].second);
    if (k + 1 < log.size() && log[k].second > p.tip_force_threshold_n) above_s += log[k + 1].first - log[k].first;
    if (log[k].second > p.tip_force_risk_n && (k == 0 || log[k - 1].second <= p.tip_force_risk_n)) ++runs;
  }
  const DebriefFigures f = m.figures(t0 + static_cast<int64_t>(30e9));
  ASSERT_TRUE(f.tip_forces_known);
  EXPECT_GT(peak, p.tip_force_risk_n) << "the approach presses the tip: the check has something to count";
  EXPECT_GT(runs, 0);
  EXPECT_DOUBLE_EQ(f.peak_tip_force_n, peak);
  EXPECT_NEAR(f.tip_force_above_threshold_s, above_s, 1e-9);
  EXPECT_EQ(f.force_events, runs);
}

}  // namespace
}  // namespace pcisim::server
