// Every client program's LCM handlers under every malformed shape of what they subscribe to: the
// bridge (force commands), the capture (X-ray and ultrasound frames, instrument) and the remote
// gateway (wire, status, session, instrument, X-ray and ultrasound frames). Each malformed message is counted as bad
// and nothing throws; a good message afterwards is still handled.
#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

#include "clients/bridge/bridge.h"
#include "clients/capture/capture_sink.h"
#include "protocol/channels.h"
#include "remote_test_support.h"
#include "fuzz/lcm_mutants.h"

namespace pcisim::clients {
namespace {

using namespace std::chrono_literals;

int64_t publish_all(lcm::LCM& lcm, const char* channel, const pcisim::fuzz::MessageCase& c) {
  for (const auto& m : c.mutants) lcm.publish(channel, m.bytes.data(), static_cast<unsigned>(m.bytes.size()));
  return static_cast<int64_t>(c.mutants.size());
}

struct StillDevice : InstrumentDevice {
  bool read(double, InstrumentReading& out) override {
    out = {};
    return true;
  }
  std::string describe() const override { return "still"; }
};

TEST(HostileLcm, BridgeCountsEveryMalformedForceCommand) {
  lcm::LCM lcm("memq://");
  StillDevice device;
  BridgeOptions o;
  o.duration_s = 1.0;
  o.log_each_second = false;
  o.fifo_priority = 0;
  Bridge bridge(lcm, device, o);
  std::atomic<bool> stop{false};
  BridgeStats stats;
  std::thread run([&] { stats = bridge.run(stop); });
  std::this_thread::sleep_for(100ms);
  const auto force = pcisim::fuzz::force_case();
  const int64_t sent = publish_all(lcm, protocol::kForceChannel, force);
  lcm.publish(protocol::kForceChannel, force.good.data(), static_cast<unsigned>(force.good.size()));
  run.join();
  EXPECT_EQ(stats.forces_bad, sent);
  EXPECT_EQ(stats.forces_received, 1) << "the good command after the flood";
}

TEST(HostileLcm, CaptureCountsEveryMalformedFrameAndSampleAndWritesNone) {
  const std::string dir = ::testing::TempDir() + "/hostile-capture";
  std::filesystem::remove_all(dir);
  FrameWriter writer(dir);
  CaptureSink sink(writer, 0, /*only_while_pedal=*/true);
  lcm::LCM images("memq://"), control("memq://");
  images.subscribe(protocol::kXrayChannel, &CaptureSink::on_frame, &sink);
  images.subscribe(protocol::kUltrasoundChannel, &CaptureSink::on_ultrasound, &sink);
  control.subscribe(protocol::kInstrumentChannel, &CaptureSink::on_instrument, &sink);
  const auto frames = pcisim::fuzz::xray_case();
  const auto us_frames = pcisim::fuzz::us_frame_case();
  const auto instrument = pcisim::fuzz::instrument_case();
  const int64_t bad_frames = publish_all(images, protocol::kXrayChannel, frames);
  const int64_t bad_us_frames = publish_all(images, protocol::kUltrasoundChannel, us_frames);
  const int64_t bad_samples = publish_all(control, protocol::kInstrumentChannel, instrument);
  while (images.handleTimeout(10) > 0 || control.handleTimeout(10) > 0) {}
  EXPECT_EQ(sink.bad(), bad_frames);
  EXPECT_EQ(sink.bad_ultrasound(), bad_us_frames);
  EXPECT_EQ(sink.bad_instrument(), bad_samples);
  EXPECT_EQ(writer.written(), 0);
  EXPECT_TRUE(sink.error().empty());
  // a good pedal-down sample, then a good frame: written
  pcisim_lcm::instrument_state_t pedal{};
  pedal.buttons = pcisim_lcm::instrument_state_t::BUTTON_FLUORO_PEDAL;
  control.publish(protocol::kInstrumentChannel, &pedal);
  control.handleTimeout(100);
  images.publish(protocol::kXrayChannel, frames.good.data(), static_cast<unsigned>(frames.good.size()));
  images.handleTimeout(100);
  EXPECT_EQ(writer.written(), 1);
  images.publish(protocol::kUltrasoundChannel, us_frames.good.data(), static_cast<unsigned>(us_frames.good.size()));
  images.handleTimeout(100);
  EXPECT_EQ(writer.written_ultrasound(), 1);
  std::filesystem::remove_all(dir);
}

TEST(HostileLcm, GatewayCountsEveryMalformedMessageOnEveryChannel) {
  remote::test::TestGateway g;
  int64_t control_sent = 0;
  control_sent += publish_all(g.control, protocol::kWireChannel, pcisim::fuzz::wire_case());
  control_sent += publish_all(g.control, protocol::kStatusChannel, pcisim::fuzz::status_case());
  control_sent += publish_all(g.control, protocol::kMetricsChannel, pcisim::fuzz::metrics_case());
  control_sent += publish_all(g.control, protocol::kSessionChannel, pcisim::fuzz::session_case());
  control_sent += publish_all(g.control, protocol::kInstrumentChannel, pcisim::fuzz::instrument_case());
  const auto frames = pcisim::fuzz::xray_case();
  const int64_t frames_sent = publish_all(g.images, protocol::kXrayChannel, frames);
  g.images.publish(protocol::kXrayChannel, frames.good.data(), static_cast<unsigned>(frames.good.size()));
  const auto us_frames = pcisim::fuzz::us_frame_case();
  const int64_t us_frames_sent = publish_all(g.images, protocol::kUltrasoundChannel, us_frames);
  g.images.publish(protocol::kUltrasoundChannel, us_frames.good.data(), static_cast<unsigned>(us_frames.good.size()));
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < end &&
         (g.gateway->counters().control_bad < control_sent || g.gateway->counters().frames_received < 1 ||
          g.gateway->counters().ultrasound_received < 1))
    std::this_thread::sleep_for(10ms);
  const auto c = g.gateway->counters();
  EXPECT_EQ(c.control_bad, control_sent);
  EXPECT_EQ(c.frames_bad, frames_sent);
  EXPECT_EQ(c.frames_received, 1) << "the good frame after the flood";
  EXPECT_EQ(c.ultrasound_bad, us_frames_sent);
  EXPECT_EQ(c.ultrasound_received, 1) << "the good ultrasound frame after the flood";
}

}  // namespace
}  // namespace pcisim::clients
