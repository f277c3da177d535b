// The once-a-second status message (sim_status_t) on the send thread's path: the server's report
// gathered into the send thread's message in place, and published through LcmIo's encoded buffer
#include <gtest/gtest.h>

#include <algorithm>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <string>
#include <vector>

#include "pcisim_lcm/session_metrics_t.hpp"
#include "pcisim_lcm/sim_status_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/allocation_count.h"
#include "anatomy/vessel/vessel_tree.h"
#include "realtime/clock.h"
#include "server/debrief/session_metrics.h"
#include "server/lcm_io.h"
#include "server/scene/scene.h"
#include "server/server.h"

namespace pcisim::server {
namespace {

// a wire with blood in a beating heart: three physics effects, so the message carries a list of names
constexpr const char* kScene = R"({
  "name": "status",
  "effects": {"guidewire": {}, "blood_flow": {}, "heart_beat": {}}
})";

struct StatusSink {
  std::mutex mutex;
  std::vector<pcisim_lcm::sim_status_t> got;
  int bad = 0;
  void on(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::sim_status_t m;
    const bool ok = protocol::decode_checked(*r, m);
    std::lock_guard lock(mutex);
    if (ok) got.push_back(m);
    bad += !ok;
  }
};

// issue #36 item 5: the status was gathered into fresh strings and vectors each second (the
// report's effect list, the scene's effects, the message's names); now 0 operator new once warm
TEST(ServerStatus, TheStatusMessageAllocatesNothingOnceWarm) {
  lcm::LCM lcm("memq://");
  StatusSink sink;
  lcm.subscribe(protocol::kStatusChannel, &StatusSink::on, &sink);
  const Scene scene = parse_scene(kScene, "status");
  Server server(scene, lcm);
  SharedState state;
  SessionLimits limits;
  LcmIo io(
      lcm, state, limits, 8.0, [&server](pcisim_lcm::sim_status_t& m) { server.fill_status(&m); },
      [](int) -> const std::string& {
        static const std::string none;
        return none;
      });
  io.publish_status();  // warm: the message's lists and the encode buffer take their sizes
  {
    realtime::AllocationCount count;
    for (int k = 0; k < 10; ++k) io.publish_status();
    EXPECT_EQ(count.allocations(), 0);
  }
  while (lcm.handleTimeout(50) > 0) {}
  std::lock_guard lock(sink.mutex);
  EXPECT_EQ(sink.bad, 0) << "every message passes decode_checked";
  ASSERT_EQ(sink.got.size(), 11u);
  for (size_t k = 0; k < sink.got.size(); ++k) {
    const pcisim_lcm::sim_status_t& m = sink.got[k];
    EXPECT_EQ(m.seq, static_cast<int64_t>(k));
    // the same names every second, one per physics effect the scene built
    ASSERT_EQ(m.num_effects, static_cast<int32_t>(m.effect_name.size()));
    ASSERT_EQ(m.effect_name.size(), m.effect_step_ms_p50.size());
    EXPECT_GE(m.num_effects, 3);
    EXPECT_EQ(m.effect_name, sink.got.front().effect_name);
    for (const char* name : {"guidewire", "blood_flow", "heart_beat"})
      EXPECT_NE(std::find(m.effect_name.begin(), m.effect_name.end(), name), m.effect_name.end()) << name;
  }
}

// issue #35: once a second the session's figures so far go out with the status (session_metrics_t),
// as the debrief has them, and the message allocates nothing once warm
TEST(ServerStatus, TheMetricsMessageCarriesTheDebriefSoFarAndAllocatesNothingOnceWarm) {
  lcm::LCM lcm("memq://");
  std::mutex mutex;
  std::vector<pcisim_lcm::session_metrics_t> got;
  int bad = 0;
  struct Sink {
    std::mutex* mutex;
    std::vector<pcisim_lcm::session_metrics_t>* got;
    int* bad;
    void on(const lcm::ReceiveBuffer* r, const std::string&) {
      pcisim_lcm::session_metrics_t m;
      const bool ok = protocol::decode_checked(*r, m);
      std::lock_guard lock(*mutex);
      if (ok) got->push_back(m);
      *bad += !ok;
    }
  } sink{&mutex, &got, &bad};
  lcm.subscribe(protocol::kMetricsChannel, &Sink::on, &sink);
  SharedState state;
  SessionLimits limits;
  SessionMetrics metrics;
  anatomy::VesselTree tree;
  tree.branches.resize(2);
  tree.branches[0].name = "LM";
  tree.branches[1].name = "LAD";
  tree.branches[1].parent = 0;
  DebriefParams params;
  params.target_branch = "LAD";
  const int64_t t0 = realtime::monotonic_ns();
  metrics.begin_pipeline(params, tree, true, beam_geometry(750, 1100, 204.8, 204.8), t0);
  physics::WorldSnapshot s;
  s.wire_nodes_m.assign(2, Eigen::Vector3d::Zero());
  for (int k = 0; k < 3; ++k) {
    s.step = k;
    s.time_s = k / 30.0;
    s.tip_m = s.tip_rest_m = Eigen::Vector3d(0.002 * k, 0, 0);
    s.tip_branch = 1;
    s.tip_force_n = k == 1 ? 0.2 : 0.0;
    metrics.record_wire(s, 0, 0, t0);
  }
  metrics.record_injection(8.0, t0);
  for (int k = 0; k < 15; ++k) metrics.record_pulse(false);
  metrics.record_beam_time(1.0, false, 0, 0);
  LcmIo io(lcm, state, limits, 8.0, nullptr, nullptr, LcmIo::Instrument::kWire, &metrics);
  io.publish_status();  // warm
  {
    realtime::AllocationCount count;
    for (int k = 0; k < 10; ++k) io.publish_status();
    EXPECT_EQ(count.allocations(), 0);
  }
  while (lcm.handleTimeout(50) > 0) {}
  std::lock_guard lock(mutex);
  EXPECT_EQ(bad, 0);
  ASSERT_EQ(got.size(), 11u);
  const pcisim_lcm::session_metrics_t& m = got.back();
  const DebriefFigures f = metrics.figures(realtime::monotonic_ns());
  EXPECT_EQ(m.seq, 10);
  EXPECT_DOUBLE_EQ(m.tip_path_mm, 4.0);
  EXPECT_DOUBLE_EQ(m.tip_path_in_vessels_mm, 4.0);
  EXPECT_EQ(m.has_target, 1);
  EXPECT_EQ(m.target_branch, "LAD");
  EXPECT_DOUBLE_EQ(m.wrong_branch_s, 0.0);
  EXPECT_EQ(m.tip_forces_known, 1);
  EXPECT_DOUBLE_EQ(m.peak_tip_force_n, 0.2);
  EXPECT_EQ(m.force_events, 1);
  EXPECT_EQ(m.contrast_injections, 1);
  EXPECT_DOUBLE_EQ(m.contrast_ml, 8.0);
  EXPECT_EQ(m.fluoro_pulses, 15);
  EXPECT_DOUBLE_EQ(m.fluoro_time_s, 1.0);
  // 15 pulses of 50 uGy/mAs x 0.15 mAs at 0.6 m
  EXPECT_NEAR(m.air_kerma_mgy, 15 * 50 * 0.15 / 0.36 * 1e-3, 1e-12);
  EXPECT_GE(m.procedure_time_s, 0.0);
  EXPECT_LE(m.procedure_time_s, f.procedure_time_s);
}

}  // namespace
}  // namespace pcisim::server
