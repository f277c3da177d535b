// The once-a-second status message (sim_status_t) on the send thread's path: the server's report
// gathered into the send thread's message in place, and published through LcmIo's encoded buffer
#include <gtest/gtest.h>

#include <algorithm>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <string>
#include <vector>

#include "pcisim_lcm/sim_status_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/allocation_count.h"
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

}  // namespace
}  // namespace pcisim::server
