// The scripted bridge publishes at 1 kHz (within 1 %), run alone because it is about timing.
#include <gtest/gtest.h>

#include "clients/bridge/bridge.h"

namespace pcisim::clients {
namespace {

TEST(BridgeTiming, ScriptedDevicePublishesAtOneKilohertz) {
  lcm::LCM lcm("memq://");
  ScriptedDevice device(TraineeScript::parse(TraineeScript::builtin_text(), "built-in"));
  BridgeOptions o;
  o.duration_s = 3.0;
  o.log_each_second = false;
  Bridge bridge(lcm, device, o);
  std::atomic<bool> stop{false};
  const BridgeStats s = bridge.run(stop);
  const double rate_hz = (s.published - 1) / s.elapsed_s;
  EXPECT_NEAR(rate_hz, 1000.0, 10.0);
  EXPECT_NEAR(s.elapsed_s, 3.0, 0.01);
  EXPECT_EQ(s.fault_samples, 0);
}

}  // namespace
}  // namespace pcisim::clients
