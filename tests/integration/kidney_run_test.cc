// The soft-tissue scene in the server on a real in-process LCM: probe poses arrive on
// PCISIM_PROBE, the kidney is pressed, the 1 kHz loop sends a force that resists the press, and
// B-mode frames of the deformed tissue arrive on PCISIM_ULTRASOUND with the probe's geometry.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <chrono>
#include <mutex>
#include <thread>

#include "pcisim_lcm/force_command_t.hpp"
#include "pcisim_lcm/probe_state_t.hpp"
#include "pcisim_lcm/us_frame_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "server/server.h"

namespace pcisim::server {
namespace {

using namespace std::chrono_literals;

// scenes/kidney.json made lighter (coarser particles, smaller frames) for a test machine
const char* kScene = R"({
  "name": "kidney-test",
  "anatomy": {"organ": "kidney"},
  "physics_rate_hz": 30,
  "effects": {
    "soft_tissue": {"particle_radius_mm": 5},
    "probe_contact": {"start_position_mm": [0, -22.5, 0], "start_orientation_wxyz": [0.5, -0.5, -0.5, -0.5]},
    "ultrasound": {"width_px": 64, "height_px": 96, "depth_mm": 60, "frame_rate_hz": 10}
  }
})";

struct Frames {
  std::mutex mutex;
  std::vector<pcisim_lcm::us_frame_t> frames;
  void on(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::us_frame_t f;
    ASSERT_TRUE(protocol::decode_checked(*r, f));
    std::lock_guard lock(mutex);
    frames.push_back(std::move(f));
  }
};

struct Forces {
  std::mutex mutex;
  std::vector<double> axial_n;
  std::vector<int32_t> flags;
  std::vector<int64_t> utime;
  std::atomic<bool> running{false};
  void on(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::force_command_t f;
    ASSERT_TRUE(protocol::decode_checked(*r, f));
    running = true;
    std::lock_guard lock(mutex);
    axial_n.push_back(f.axial_force_n);
    flags.push_back(f.flags);
    utime.push_back(f.utime);
  }
};

double mean_abs_difference(const pcisim_lcm::us_frame_t& a, const pcisim_lcm::us_frame_t& b) {
  double sum = 0;
  for (size_t i = 0; i < a.data.size(); ++i) sum += std::abs(double(a.data[i]) - double(b.data[i]));
  return sum / static_cast<double>(a.data.size());
}

TEST(KidneyRun, AProbeOverLcmPressesTheKidneyFeelsItAndImagesIt) {
  lcm::LCM lcm("memq://");
  Frames rec;
  lcm.subscribe(protocol::kUltrasoundChannel, &Frames::on, &rec);
  Forces forces;
  lcm.subscribe(protocol::kForceChannel, &Forces::on, &forces);
  Server server(parse_scene(kScene, "kidney-test"), lcm, &lcm);

  // the probe: 5 mm above the anterior skin (y = -17.5 mm) for 1 s, pressed 8 mm in over 1 s, held
  std::atomic<bool> done{false}, pressed{false};
  std::thread probe([&] {
    while (!forces.running) std::this_thread::sleep_for(1ms);
    const auto t0 = std::chrono::steady_clock::now();
    pcisim_lcm::probe_state_t m{};
    m.orientation_wxyz[0] = 0.5;
    m.orientation_wxyz[1] = m.orientation_wxyz[2] = m.orientation_wxyz[3] = -0.5;
    for (int64_t seq = 0; !done; ++seq) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      m.seq = seq;
      m.position_mm[1] = -22.5 + 13.0 * std::clamp(t - 1.0, 0.0, 1.0);
      if (t > 2.0) pressed = true;
      lcm.publish(protocol::kProbeChannel, &m);
      std::this_thread::sleep_for(1ms);
    }
  });
  std::atomic<bool> stop{false};
  const StatsReport r = server.run(4.0, stop);
  done = true;
  probe.join();

  EXPECT_EQ(r.effects, (std::vector<std::string>{"soft_tissue", "probe_contact", "ultrasound"}));
  // the haptic loop ran throughout. Its rate is a benchmark's business: CI's Release run (two tests
  // at once, beside the ultrasound) once managed 2977 ticks in 4 s, so the windows below are read on
  // the commands' own clock, not counted in ticks
  EXPECT_GT(r.haptic_ticks, 2000);
  {
    // the force resists the press once pressed (from 2.3 s on), and is zero before. A loaded
    // machine may make a physics step late: its model goes stale and the force fades (the safety
    // layer doing its job), so the held force is judged on the ticks that were neither faded,
    // stale nor ramping in. (CI's Release run, two tests at once beside other work, once left no
    // clean tick in the last second at 4 mm particles: the scene is lighter since, and the window
    // is the whole hold)
    using F = pcisim_lcm::force_command_t;
    std::lock_guard lock(forces.mutex);
    ASSERT_GT(forces.axial_n.size(), 2000u);
    // seconds since the first command, which is when the probe's clock started
    auto t_s = [&](size_t i) { return static_cast<double>(forces.utime[i] - forces.utime[0]) * 1e-6; };
    const double end_s = t_s(forces.utime.size() - 1);
    ASSERT_GT(end_s, 3.5) << "the run lasted its 4 s";
    double held_sum = 0, early_max = 0;
    int held = 0;
    for (size_t i = 0; i < forces.axial_n.size(); ++i) {
      const double t = t_s(i);
      if (t > 0.2 && t < 0.8) early_max = std::max(early_max, std::abs(forces.axial_n[i]));
      constexpr int32_t kNotClean = int32_t{F::FLAG_FADED} | F::FLAG_STALE | F::FLAG_RAMPING | F::FLAG_FAULT;
      if (t < 2.3 || t > end_s - 0.05 || (forces.flags[i] & kNotClean)) continue;
      held_sum += forces.axial_n[i];
      ++held;
    }
    ASSERT_GT(held, 100) << "the force was faded for most of the hold";
    const double held_mean = held_sum / held;
    EXPECT_GT(held_mean, 0.1) << "pressed 8 mm into the kidney, the hand feels it push back";
    EXPECT_LT(held_mean, 10.0);
    EXPECT_LT(early_max, 0.01) << "nothing while the probe is in the air";
    std::printf("force along the probe: %.2f N pressed (%d clean ticks of the hold), %.4f N before\n", held_mean, held,
                early_max);
  }
  std::lock_guard lock(rec.mutex);
  // 10 Hz for 4 s (a busy machine may miss some)
  ASSERT_GE(rec.frames.size(), 20u);
  // the last frames may still be queued when the server's receive thread stops
  EXPECT_LE(r.ultrasound_frames - static_cast<int64_t>(rec.frames.size()), 2);
  EXPECT_GE(r.ultrasound_frames, static_cast<int64_t>(rec.frames.size()));
  const auto& first = rec.frames.front();
  const auto& last = rec.frames.back();
  EXPECT_EQ(first.width, 64);
  EXPECT_EQ(first.height, 96);
  EXPECT_EQ(first.geometry, pcisim_lcm::us_frame_t::GEOMETRY_LINEAR);
  // the geometry follows the probe: beam +y, lateral +z, the face where the probe was put
  EXPECT_NEAR(last.beam[1], 1.0, 1e-9);
  EXPECT_NEAR(last.lateral[2], 1.0, 1e-9);
  EXPECT_NEAR(first.origin_mm[1], -22.5, 1e-6);
  EXPECT_NEAR(last.origin_mm[1], -9.5, 0.05);
  EXPECT_GT(-last.probe_force_n[1], 0.1) << "the tissue pushes the probe back (-beam)";
  // the picture: something echoes, and pressing changes it (the organ moved under the probe)
  double mean_grey = 0;
  for (uint8_t g : last.data) mean_grey += g / double(last.data.size());
  EXPECT_GT(mean_grey, 5.0);
  EXPECT_GT(mean_abs_difference(first, last), 2.0);
  std::printf("%zu frames; mean grey %.1f; first vs last differ by %.1f grey levels\n", rec.frames.size(), mean_grey,
              mean_abs_difference(first, last));
}

}  // namespace
}  // namespace pcisim::server
