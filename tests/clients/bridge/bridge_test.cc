#include "clients/bridge/bridge.h"

#include <gtest/gtest.h>

#include <cmath>
#include <mutex>

#include "clients/bridge/probe_script.h"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/probe_state_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/allocation_count.h"

namespace pcisim::clients {
namespace {

using I = pcisim_lcm::instrument_state_t;

// a device that moves forward, goes into fault for a while, then comes back
struct FlakyDevice : InstrumentDevice {
  bool read(double t_s, InstrumentReading& out) override {
    if (t_s > 0.10 && t_s < 0.20) return false;
    out.insertion_mm = 100.0 * t_s;
    out.insertion_rate_mm_s = 100.0;
    return true;
  }
  std::string describe() const override { return "flaky"; }
};

// every message of one type on its channel, each through the decoder's checks
template <class Message>
struct Sink {
  std::mutex mutex;
  std::vector<Message> samples;
  int bad = 0;
  void on(const lcm::ReceiveBuffer* r, const std::string&) {
    Message m;
    const bool ok = protocol::decode_checked(*r, m);
    std::lock_guard lock(mutex);
    if (ok) samples.push_back(m);
    bad += !ok;
  }
};

TEST(Bridge, AFaultyDeviceIsPublishedAsFaultWithNoMotion) {
  lcm::LCM lcm("memq://");
  Sink<I> sink;
  lcm.subscribe(protocol::kInstrumentChannel, &Sink<I>::on, &sink);
  FlakyDevice device;
  BridgeOptions o;
  o.duration_s = 0.3;
  o.log_each_second = false;
  Bridge bridge(lcm, device, o);
  std::atomic<bool> stop{false};
  const BridgeStats s = bridge.run(stop);
  while (lcm.handleTimeout(50) > 0) {}
  // the fault lasts a third of the run; a loaded machine skips ticks (missed periods are not
  // published late), so counts are checked against what was published, not against 1 kHz
  EXPECT_GE(s.fault_samples, 3);
  EXPECT_GE(5 * s.fault_samples, s.published) << "about a third of the samples are in fault";
  std::lock_guard lock(sink.mutex);
  EXPECT_EQ(sink.bad, 0);
  ASSERT_EQ(static_cast<int64_t>(sink.samples.size()), s.published);
  double held = -1, last_ok = -1;
  int faults = 0, ok_after = 0;
  for (const auto& m : sink.samples) {
    if (m.status == I::STATUS_FAULT) {
      ++faults;
      if (held < 0) held = m.insertion_mm;
      EXPECT_DOUBLE_EQ(m.insertion_mm, held) << "no motion while in fault";
      EXPECT_EQ(m.insertion_rate_mm_s, 0.0);
    } else if (faults > 0) {
      ++ok_after;
    } else {
      last_ok = m.insertion_mm;
    }
  }
  EXPECT_EQ(faults, s.fault_samples);
  EXPECT_DOUBLE_EQ(held, last_ok) << "the fault holds the last good position";
  EXPECT_LE(held, 10.0 + 1e-9) << "read before the fault began at 0.1 s";
  EXPECT_GT(held, 5.0);
  EXPECT_GE(ok_after, 3) << "the device came back";
  EXPECT_GE(5 * ok_after, s.published) << "for about a third of the run";
  for (size_t i = 1; i < sink.samples.size(); ++i) EXPECT_EQ(sink.samples[i].seq, sink.samples[i - 1].seq + 1);
}

// a probe bridge publishes the script's pose on PCISIM_PROBE, and no instrument
TEST(Bridge, AProbeBridgePublishesTheScriptsPoseAndNoInstrument) {
  using P = pcisim_lcm::probe_state_t;
  // 100 mm/s along x and 90 deg about z over 0.2 s; then held, frozen, at a depth of 80 mm
  const auto script = ProbeScript::parse(R"({"name": "sweep", "keyframes": [
      {"t_s": 0, "position_mm": [0, -20, 5], "orientation_wxyz": [1, 0, 0, 0]},
      {"t_s": 0.2, "position_mm": [20, -20, 5], "orientation_wxyz": [0.7071067811865476, 0, 0, 0.7071067811865476],
       "depth_mm": 80, "gain_db": 6, "freeze": true}]})",
                                         "sweep.json");
  lcm::LCM lcm("memq://");
  Sink<P> probes;
  Sink<I> instruments;
  lcm.subscribe(protocol::kProbeChannel, &Sink<P>::on, &probes);
  lcm.subscribe(protocol::kInstrumentChannel, &Sink<I>::on, &instruments);
  BridgeOptions o;
  o.duration_s = 0.3;
  o.log_each_second = false;
  o.device_id = 7;
  Bridge bridge(lcm, script, o);
  std::atomic<bool> stop{false};
  const BridgeStats s = bridge.run(stop);
  while (lcm.handleTimeout(50) > 0) {}
  EXPECT_EQ(s.fault_samples, 0);
  std::lock_guard lock(probes.mutex);
  EXPECT_EQ(probes.bad, 0) << "every message passes decode_checked";
  ASSERT_EQ(static_cast<int64_t>(probes.samples.size()), s.published);
  // about 300 at 1 kHz; a loaded machine skips ticks, so the counts below are shares of these
  EXPECT_GE(s.published, 30);
  EXPECT_TRUE(instruments.samples.empty() && instruments.bad == 0) << "a probe bridge publishes no instrument";

  // the bridge's clock starts just before the first message: its utime is the script's t = 0
  const int64_t t0_us = probes.samples.front().utime;
  int moving = 0, held = 0;
  for (size_t i = 0; i < probes.samples.size(); ++i) {
    const P& m = probes.samples[i];
    if (i > 0) {
      EXPECT_EQ(m.seq, probes.samples[i - 1].seq + 1);
    }
    EXPECT_EQ(m.device_id, 7);
    EXPECT_EQ(m.status, P::STATUS_OK);
    const double t_s = (m.utime - t0_us) * 1e-6;
    const ProbeReading want = script.sample(t_s);
    // 0.2 mm, 0.02 rad: 2 ms of the script, the slack between the bridge's clock and utime's
    EXPECT_NEAR(m.position_mm[0], want.position_mm[0], 0.2) << "t = " << t_s;
    EXPECT_EQ(m.position_mm[1], -20.0);
    EXPECT_EQ(m.position_mm[2], 5.0);
    const double angle_rad = 2 * std::atan2(m.orientation_wxyz[3], m.orientation_wxyz[0]);
    EXPECT_NEAR(angle_rad, 2 * std::atan2(want.orientation_wxyz[3], want.orientation_wxyz[0]), 0.02) << t_s;
    if (t_s < 0.195) {
      ++moving;
      EXPECT_EQ(m.depth_mm, 0.0);
      EXPECT_EQ(m.gain_db, 0.0);
      EXPECT_EQ(m.buttons, 0);
    } else if (t_s > 0.205) {
      ++held;
      EXPECT_EQ(m.position_mm[0], 20.0);
      EXPECT_EQ(m.depth_mm, 80.0);
      EXPECT_EQ(m.gain_db, 6.0);
      EXPECT_EQ(m.buttons, P::BUTTON_FREEZE);
    }
  }
  EXPECT_GE(2 * moving, s.published) << "moving for two thirds of the run";
  EXPECT_GE(5 * held, s.published) << "held for the last third";
}

// the publishing thread's allocations over one run (its start allocates: the receive thread)
long allocations_of_a_run(lcm::LCM& lcm, Bridge& bridge) {
  std::atomic<bool> stop{false};
  pcisim::realtime::AllocationCount count;
  bridge.run(stop);
  const long n = count.allocations();
  while (lcm.handleTimeout(0) > 0) {}
  return n;
}

// past its start the 1 kHz loop allocates nothing, instrument or probe: a run four times as long
// allocates as much (operator new on the publishing thread; liblcm's own mallocs are not counted)
TEST(Bridge, ItsLoopAllocatesNothingPerTick) {
  lcm::LCM lcm("memq://");
  ScriptedDevice trainee(TraineeScript::parse(TraineeScript::builtin_text(), "built-in"));
  const auto probe = ProbeScript::parse(ProbeScript::builtin_text(), "built-in");
  BridgeOptions o;
  o.log_each_second = false;
  for (const bool is_probe : {false, true}) {
    // the first run warms up what is made once per process
    const double durations_s[3] = {0.02, 0.05, 0.2};
    long allocations[3] = {};
    for (int i = 0; i < 3; ++i) {
      o.duration_s = durations_s[i];
      Bridge bridge = is_probe ? Bridge(lcm, probe, o) : Bridge(lcm, trainee, o);
      allocations[i] = allocations_of_a_run(lcm, bridge);
    }
    EXPECT_EQ(allocations[2], allocations[1]) << (is_probe ? "probe" : "instrument");
    EXPECT_LT(allocations[1], 20) << (is_probe ? "probe" : "instrument");
  }
}

}  // namespace
}  // namespace pcisim::clients
