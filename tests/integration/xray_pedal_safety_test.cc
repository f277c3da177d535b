// The instrument's fluoroscopy pedal keeps the beam on only while the instrument is heard and not
// in fault: a faulted box or a crashed bridge with the pedal down must not leave the beam on.
#include <gtest/gtest.h>

#include <chrono>
#include <mutex>
#include <thread>

#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "server/server.h"

namespace pcisim::server {
namespace {

using namespace std::chrono_literals;
using I = pcisim_lcm::instrument_state_t;

const char* kScene = R"({
  "name": "pedal-safety",
  "effects": {
    "guidewire": {"segments": 60},
    "xray": {"detector_px": 128, "pixel_mm": 1.6, "volume_voxels": 128, "volume_spacing_mm": 2.8, "pulse_rate_fps": 15}
  }
})";

struct FrameTimes {
  std::mutex mutex;
  std::vector<double> sim_s;
  std::atomic<bool> running{false};
  void on_frame(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::xray_frame_t f;
    if (!protocol::decode_checked(*r, f)) return;
    std::lock_guard lock(mutex);
    sim_s.push_back(f.sim_time_s);
  }
  void on_force(const lcm::ReceiveBuffer*, const std::string&) { running = true; }
  int between(double a, double b) {
    std::lock_guard lock(mutex);
    return static_cast<int>(std::count_if(sim_s.begin(), sim_s.end(), [&](double t) { return t >= a && t < b; }));
  }
};

TEST(XrayPedalSafety, FaultOrSilenceWithThePedalDownTurnsTheBeamOff) {
  lcm::LCM lcm("memq://");
  FrameTimes rec;
  lcm.subscribe(protocol::kXrayChannel, &FrameTimes::on_frame, &rec);
  lcm.subscribe(protocol::kForceChannel, &FrameTimes::on_force, &rec);
  Server server(parse_scene(kScene, "pedal-safety"), lcm, &lcm);
  std::atomic<bool> done{false};
  // the pedal is held down throughout: OK until 1.0 s, in fault until 1.5 s, OK again until
  // 2.0 s, then the bridge dies (nothing more is published)
  std::thread instrument([&] {
    while (!rec.running && !done) std::this_thread::sleep_for(1ms);
    const auto t0 = std::chrono::steady_clock::now();
    I m{};
    m.buttons = I::BUTTON_FLUORO_PEDAL;
    for (int64_t seq = 0; !done; ++seq) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (t >= 2.0) break;
      m.seq = seq;
      m.status = t >= 1.0 && t < 1.5 ? I::STATUS_FAULT : I::STATUS_OK;
      lcm.publish(protocol::kInstrumentChannel, &m);
      std::this_thread::sleep_for(1ms);
    }
  });
  std::atomic<bool> stop{false};
  server.run(3.2, stop);
  done = true;
  instrument.join();
  // sim time runs from the server's start, which the instrument's clock follows within a few ms
  EXPECT_GE(rec.between(0.2, 1.0), 8) << "pedal down, instrument heard: frames";
  EXPECT_EQ(rec.between(1.15, 1.5), 0) << "instrument in fault: no beam, though its pedal bit is set";
  EXPECT_GE(rec.between(1.6, 2.0), 3) << "back from fault, pedal still down: frames again";
  EXPECT_EQ(rec.between(2.4, 3.2), 0) << "the bridge went silent: the beam went off after the timeout";
}

}  // namespace
}  // namespace pcisim::server
