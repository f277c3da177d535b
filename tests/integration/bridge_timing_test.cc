// The scripted bridge keeps a 1 kHz schedule: every period is either published or counted as missed,
// and on a shared machine it still publishes at least half of them. Run alone because it is about timing; the
// wake-up figures themselves live in the haptics benchmark, not here.
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
  EXPECT_NEAR(s.elapsed_s, 3.0, 0.01);
  // each of the ~3000 deadlines was either published or skipped and counted, none lost or doubled
  EXPECT_NEAR(static_cast<double>(s.published + s.missed_periods), 1000.0 * s.elapsed_s + 1.0, 3.0);
  EXPECT_GT(rate_hz, 500.0) << s.missed_periods << " periods missed: half the rate is broken, less is a busy machine";
  EXPECT_LE(rate_hz, 1001.0) << "never faster than the schedule";
  EXPECT_EQ(s.fault_samples, 0);
}

}  // namespace
}  // namespace pcisim::clients
