// The server with fluoroscopy on a real in-process LCM: frames only while a pedal is down, at the
// pulse rate, with exact geometry and labels; C-arm and contrast commands change what they show.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <chrono>
#include <mutex>
#include <thread>

#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/session_command_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"
#include "pcisim_lcm/sim_status_t.hpp"
#include "pcisim_lcm/wire_state_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/clock.h"
#include "server/server.h"

namespace pcisim::server {
namespace {

using C = pcisim_lcm::session_command_t;
using namespace std::chrono_literals;

const char* kScene = R"({
  "name": "xray-test",
  "effects": {
    "guidewire": {"segments": 100},
    "vessel_contact": {},
    "xray": {"detector_px": 128, "pixel_mm": 1.6, "volume_voxels": 128, "volume_spacing_mm": 2.8, "pulse_rate_fps": 15},
    "contrast": {},
    "detector_noise": {"photons_per_pixel": 5000}
  }
})";

struct Frames {
  std::mutex mutex;
  std::vector<pcisim_lcm::xray_frame_t> frames;
  std::vector<double> arrival_s;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  void on(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::xray_frame_t f;
    ASSERT_TRUE(protocol::decode_checked(*r, f));
    std::lock_guard lock(mutex);
    frames.push_back(std::move(f));
    arrival_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
};

void send(lcm::LCM& lcm, int8_t command, int8_t pedal = 0, double primary = 0, double secondary = 0,
          double contrast_ml = 0, double contrast_ml_s = 0) {
  C c{};
  c.command = command;
  c.pedal_down = pedal;
  c.primary_angle_deg = primary;
  c.secondary_angle_deg = secondary;
  c.contrast_ml = contrast_ml;
  c.contrast_ml_s = contrast_ml_s;
  lcm.publish(protocol::kSessionChannel, &c);
}

double mean_abs_difference(const pcisim_lcm::xray_frame_t& a, const pcisim_lcm::xray_frame_t& b) {
  const auto* pa = reinterpret_cast<const uint16_t*>(a.data.data());
  const auto* pb = reinterpret_cast<const uint16_t*>(b.data.data());
  double sum = 0;
  for (int i = 0; i < a.width * a.height; ++i) sum += std::abs(double(pa[i]) - double(pb[i]));
  return sum / (a.width * a.height);
}

struct Statuses {
  std::mutex mutex;
  std::vector<pcisim_lcm::sim_status_t> all;
  void on(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::sim_status_t m;
    ASSERT_TRUE(protocol::decode_checked(*r, m));
    std::lock_guard lock(mutex);
    all.push_back(std::move(m));
  }
};

// the wire states as the bus carried them (what lcm-logger would record)
struct WireStates {
  std::mutex mutex;
  std::vector<pcisim_lcm::wire_state_t> all;
  void on(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::wire_state_t m;
    ASSERT_TRUE(protocol::decode_checked(*r, m));
    std::lock_guard lock(mutex);
    all.push_back(std::move(m));
  }
};

// set by the server's first force command: its loops are running
struct Started {
  std::atomic<bool> running{false};
  void on(const lcm::ReceiveBuffer*, const std::string&) { running = true; }
};

TEST(XrayRun, PedalCarmAndContrastDriveTheFrames) {
  lcm::LCM lcm("memq://");
  Frames rec;
  lcm.subscribe(protocol::kXrayChannel, &Frames::on, &rec);
  Statuses statuses;
  lcm.subscribe(protocol::kStatusChannel, &Statuses::on, &statuses);
  // a steady instrument with the wire pushed in 20 mm
  std::atomic<bool> done{false};
  std::thread instrument([&] {
    pcisim_lcm::instrument_state_t m{};
    for (int64_t seq = 0; !done; ++seq) {
      m.seq = seq;
      m.insertion_mm = std::min(20.0, 0.02 * seq);
      lcm.publish(protocol::kInstrumentChannel, &m);
      std::this_thread::sleep_for(1ms);
    }
  });
  // the console keeps its schedule from the server's start (its first force command), on absolute
  // deadlines, so a slow start or a late wake-up on a busy machine does not shift the later commands
  Started started;
  lcm::Subscription* first_force = lcm.subscribe(protocol::kForceChannel, &Started::on, &started);
  WireStates wires;
  lcm.subscribe(protocol::kWireChannel, &WireStates::on, &wires);
  // the session's debrief figures (issue #35), checked below against the script and the bus
  SessionMetrics metrics;
  Server server(parse_scene(kScene, "xray-test"), lcm, &lcm, nullptr, &metrics);
  // a debrief asked for by a session command is written on run()'s thread (CMD_DEBRIEF)
  std::atomic<int> debriefs{0};
  std::atomic<bool> debrief_off_rx{false};
  const std::thread::id test_thread = std::this_thread::get_id();
  server.on_debrief_request = [&] {
    ++debriefs;
    debrief_off_rx = std::this_thread::get_id() == test_thread;
  };
  std::chrono::steady_clock::time_point pedal_down, pedal_up;
  std::thread console([&] {
    while (!started.running) std::this_thread::sleep_for(1ms);
    const auto t0 = std::chrono::steady_clock::now();
    std::this_thread::sleep_until(t0 + 1500ms);
    pedal_down = std::chrono::steady_clock::now();
    send(lcm, C::CMD_FLUORO_PEDAL, 1);  // frames from 1.5 s
    std::this_thread::sleep_until(t0 + 2500ms);
    send(lcm, C::CMD_CARM, 0, 40, 25);  // LAO 40 CRA 25 from 2.5 s
    std::this_thread::sleep_until(t0 + 3000ms);
    send(lcm, C::CMD_CONTRAST, 0, 0, 0, 5.0, 5.0);  // inject 5 ml over 1 s at 3 s
    std::this_thread::sleep_until(t0 + 4500ms);
    send(lcm, C::CMD_FLUORO_PEDAL, 0);  // no frames after 4.5 s
    pedal_up = std::chrono::steady_clock::now();
    std::this_thread::sleep_until(t0 + 4800ms);
    send(lcm, C::CMD_DEBRIEF);
  });
  std::atomic<bool> stop{false};
  const StatsReport r = server.run(5.5, stop);
  console.join();
  done = true;
  instrument.join();
  lcm.unsubscribe(first_force);

  {
    // the once-a-second status reports the session's cath-lab figures: the last one (after the
    // pedal came up at 4.5 s) has 3 s of beam, the C-arm where it was moved, the one injection
    // with the volume its command named
    std::lock_guard lock(statuses.mutex);
    ASSERT_GE(statuses.all.size(), 4u);
    const auto& last = statuses.all.back();
    EXPECT_NEAR(last.fluoro_time_s, 3.0, 0.2);
    EXPECT_EQ(last.fluoro_on, 0);
    EXPECT_DOUBLE_EQ(last.carm_primary_deg, 40.0);
    EXPECT_DOUBLE_EQ(last.carm_secondary_deg, 25.0);
    EXPECT_EQ(last.contrast_injections, 1);
    EXPECT_DOUBLE_EQ(last.contrast_ml, 5.0);
    EXPECT_EQ(statuses.all.front().contrast_injections, 0);
  }
  std::lock_guard lock(rec.mutex);
  ASSERT_GT(rec.frames.size(), 30u);
  // simulation time runs with the server's clock from the start of run()
  EXPECT_GT(rec.frames.front().sim_time_s, 1.4) << "no frame before the pedal";
  EXPECT_LT(rec.frames.back().sim_time_s, 4.7) << "no frame after the pedal came up";
  const double span = rec.arrival_s.back() - rec.arrival_s.front();
  // the pulse rate: never faster; slower only by the pulses a busy machine makes the renderer miss
  // (the frame rate under load is the x-ray benchmark's business)
  EXPECT_LE((rec.frames.size() - 1) / span, 15.5) << "the pulse rate";
  EXPECT_GT((rec.frames.size() - 1) / span, 11.0) << "the pulse rate";
  EXPECT_EQ(r.xray_frames, static_cast<int64_t>(rec.frames.size()));
  EXPECT_LE(r.xray_fps, 15.5);
  EXPECT_GT(r.xray_fps, 11.0);
  EXPECT_NE(std::find(r.effects.begin(), r.effects.end(), "detector_noise"), r.effects.end());

  // every frame's wire labels re-project from its stated geometry (independent of the renderer)
  for (const auto& f : rec.frames) {
    ASSERT_GT(f.num_wire_points, 10);
    const Eigen::Vector3d s(f.source_mm), c(f.detector_center_mm), u(f.detector_u), v(f.detector_v);
    const Eigen::Vector3d n = u.cross(v).normalized();
    for (int i = 0; i < f.num_wire_points; i += 7) {
      const Eigen::Vector3d p(f.wire_mm[i][0], f.wire_mm[i][1], f.wire_mm[i][2]);
      const double t = (c - s).dot(n) / (p - s).dot(n);
      const Eigen::Vector3d hit = s + t * (p - s);
      const double col = (hit - c).dot(u) / f.pixel_mm + 0.5 * (f.width - 1);
      const double row = (hit - c).dot(v) / f.pixel_mm + 0.5 * (f.height - 1);
      EXPECT_NEAR(col, f.wire_px[i][0], 0.5);
      EXPECT_NEAR(row, f.wire_px[i][1], 0.5);
    }
  }
  // the C-arm command moved the view; contrast showed up after the injection
  const auto& before = rec.frames[3];
  const auto& after = rec.frames[rec.frames.size() / 2 + 2];
  EXPECT_DOUBLE_EQ(before.primary_angle_deg, -30.0);
  EXPECT_DOUBLE_EQ(after.primary_angle_deg, 40.0);
  EXPECT_DOUBLE_EQ(after.secondary_angle_deg, 25.0);
  EXPECT_GT(mean_abs_difference(before, after), 500.0) << "another view, another image";
  int with_contrast_before = 0, with_contrast_after = 0;
  for (size_t i = 0; i < rec.frames.size(); ++i) {
    const bool has = rec.frames[i].num_contrast_branches > 0;
    (rec.frames[i].sim_time_s < 2.9 ? with_contrast_before : with_contrast_after) += has;
  }
  EXPECT_EQ(with_contrast_before, 0);
  EXPECT_GT(with_contrast_after, 5);

  // the debrief (issue #35): the beam's time is the x-ray thread's (the status's last figure, after
  // the pedal came up), and within the status's bound of the time the script held the pedal (the
  // thread sees the pedal at its ticks, and a busy machine's late ticks shorten it)
  EXPECT_EQ(debriefs.load(), 1);
  EXPECT_TRUE(debrief_off_rx.load()) << "written on run()'s thread, not the receive thread";
  const DebriefFigures f = metrics.figures(realtime::monotonic_ns());
  const double pressed_s = std::chrono::duration<double>(pedal_up - pedal_down).count();
  {
    std::lock_guard lock(statuses.mutex);
    EXPECT_NEAR(f.fluoro_time_s, statuses.all.back().fluoro_time_s, 1e-6);
  }
  EXPECT_NEAR(f.fluoro_time_s, pressed_s, 0.2) << "pressed " << pressed_s << " s";
  EXPECT_EQ(f.cine_runs, 0);
  EXPECT_EQ(f.contrast_injections, 1);
  EXPECT_DOUBLE_EQ(f.contrast_ml, 5.0) << "the volume commanded";
  // the pulses: every frame but the C-arm move's refresh (one move: at most one extra frame); the
  // dose a pulse is the scene's C-arm's (SAD 750, SID 1100 mm): 50 uGy/mAs 0.15 mAs / 0.6^2 m^2
  EXPECT_LE(f.fluoro_pulses, static_cast<int64_t>(rec.frames.size()));
  EXPECT_GE(f.fluoro_pulses, static_cast<int64_t>(rec.frames.size()) - 1);
  EXPECT_NEAR(f.air_kerma_mgy, f.fluoro_pulses * 50 * 0.15 / 0.36 * 1e-3, 1e-9);
  // the two poses the beam was on at, their beam times adding up to the whole
  ASSERT_EQ(f.carm_poses.size(), 2u);
  EXPECT_DOUBLE_EQ(f.carm_poses[0].primary_deg, -30.0);
  EXPECT_DOUBLE_EQ(f.carm_poses[1].primary_deg, 40.0);
  EXPECT_NEAR(f.carm_poses[0].beam_s + f.carm_poses[1].beam_s, f.fluoro_time_s, 1e-9);
  // the tip's path: the one integrated here from the wire states the bus carried (as lcm-logger
  // records them), step by step
  std::lock_guard wire_lock(wires.mutex);
  ASSERT_GT(wires.all.size(), 100u);
  EXPECT_EQ(f.wire_states, static_cast<int64_t>(wires.all.size()));
  double path_mm = 0.0;
  for (size_t k = 1; k < wires.all.size(); ++k) {
    ASSERT_GT(wires.all[k].seq, wires.all[k - 1].seq);
    const Eigen::Vector3d a(wires.all[k - 1].tip_mm), b(wires.all[k].tip_mm);
    path_mm += (b - a).norm();
  }
  EXPECT_GT(path_mm, 10.0) << "the wire was pushed in 20 mm (its first millimetres inside the catheter)";
  EXPECT_NEAR(f.tip_path_mm, path_mm, 1e-9 * path_mm);
  EXPECT_TRUE(to_json(f).at("peak_tip_force_n").is_null()) << "the chain-mail computes no wall force";
}

}  // namespace
}  // namespace pcisim::server
