#include "clients/bridge/bridge.h"

#include <gtest/gtest.h>

#include <mutex>

#include "pcisim_lcm/instrument_state_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"

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

struct Sink {
  std::mutex mutex;
  std::vector<I> samples;
  void on(const lcm::ReceiveBuffer* r, const std::string&) {
    I m;
    ASSERT_TRUE(protocol::decode_checked(*r, m));
    std::lock_guard lock(mutex);
    samples.push_back(m);
  }
};

TEST(Bridge, AFaultyDeviceIsPublishedAsFaultWithNoMotion) {
  lcm::LCM lcm("memq://");
  Sink sink;
  lcm.subscribe(protocol::kInstrumentChannel, &Sink::on, &sink);
  FlakyDevice device;
  BridgeOptions o;
  o.duration_s = 0.3;
  o.log_each_second = false;
  Bridge bridge(lcm, device, o);
  std::atomic<bool> stop{false};
  const BridgeStats s = bridge.run(stop);
  while (lcm.handleTimeout(50) > 0) {}
  EXPECT_GT(s.fault_samples, 50);
  std::lock_guard lock(sink.mutex);
  ASSERT_EQ(static_cast<int64_t>(sink.samples.size()), s.published);
  double held = -1;
  int faults = 0, ok_after = 0;
  for (const auto& m : sink.samples) {
    if (m.status == I::STATUS_FAULT) {
      ++faults;
      if (held < 0) held = m.insertion_mm;
      EXPECT_DOUBLE_EQ(m.insertion_mm, held) << "no motion while in fault";
      EXPECT_EQ(m.insertion_rate_mm_s, 0.0);
    } else if (faults > 0) {
      ++ok_after;
    }
  }
  EXPECT_EQ(faults, s.fault_samples);
  EXPECT_NEAR(held, 10.0, 0.5) << "the last good position before the fault";
  EXPECT_GT(ok_after, 50) << "the device came back";
  for (size_t i = 1; i < sink.samples.size(); ++i) EXPECT_EQ(sink.samples[i].seq, sink.samples[i - 1].seq + 1);
}

}  // namespace
}  // namespace pcisim::clients
