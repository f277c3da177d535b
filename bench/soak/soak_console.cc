// pcisim-soak-console: the console side of scripts/soak. It plays an instructor who keeps the beam
// on, moves the C-arm, injects contrast and reloads the scene on a schedule, and it watches what a
// trainee must never get: a non-finite force or one beyond the scene's peak. It also counts the
// frames it receives and keeps the newest status. Writes one JSON summary at the end.
#include <CLI/CLI.hpp>
#include <atomic>
#include <cmath>
#include <csignal>
#include <fstream>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <random>
#include <thread>

#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/clock.h"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) {
  g_stop = true;
}

using pcisim::realtime::monotonic_ns;

struct Watch {
  double peak_force_n = 4.0, peak_torque_nmm = 20.0;
  int64_t forces = 0, forces_bad = 0, forces_non_finite = 0, forces_over_peak = 0;
  double max_abs_force_n = 0, max_abs_torque_nmm = 0;
  int64_t statuses = 0, status_bad = 0;
  nlohmann::json last_status = nlohmann::json::object();
  int64_t frames_received = 0, frames_bad = 0;
  pcisim_lcm::force_command_t force;
  pcisim_lcm::sim_status_t status;
  pcisim_lcm::xray_frame_t frame;

  void on_force(const lcm::ReceiveBuffer* r, const std::string&) {
    // decoded without the finite check, which would hide a non-finite force from the server; the
    // flood's well-formed messages carry utime <= 0 and are not the server's
    int used = -1;
    try {
      used = force.decode(r->data, 0, static_cast<int>(r->data_size));
    } catch (...) {}
    if (used != static_cast<int>(r->data_size) || force.utime <= 0) {
      ++forces_bad;
      return;
    }
    ++forces;
    if (!std::isfinite(force.axial_force_n) || !std::isfinite(force.torque_nmm)) ++forces_non_finite;
    const double f = std::abs(force.axial_force_n), t = std::abs(force.torque_nmm);
    if (f > peak_force_n * (1 + 1e-9) || t > peak_torque_nmm * (1 + 1e-9)) ++forces_over_peak;
    max_abs_force_n = std::max(max_abs_force_n, f);
    max_abs_torque_nmm = std::max(max_abs_torque_nmm, t);
  }
  void on_status(const lcm::ReceiveBuffer* r, const std::string&) {
    if (!pcisim::protocol::decode_checked(*r, status)) {
      ++status_bad;
      return;
    }
    ++statuses;
    last_status = {{"lcm_rx", status.lcm_rx},
                   {"lcm_dropped_bad", status.lcm_dropped_bad},
                   {"xray_frames", status.xray_frames},
                   {"contrast_injections", status.contrast_injections},
                   {"contrast_ml", status.contrast_ml},
                   {"haptic_rate_hz", status.haptic_rate_hz},
                   {"physics_rate_hz", status.physics_rate_hz},
                   {"haptic_overruns", status.haptic_overruns}};
  }
  void on_frame(const lcm::ReceiveBuffer* r, const std::string&) {
    if (!pcisim::protocol::decode_checked(*r, frame)) {
      ++frames_bad;
      return;
    }
    ++frames_received;
  }
};

pcisim_lcm::session_command_t command(int8_t cmd, int64_t seq) {
  pcisim_lcm::session_command_t c{};
  c.utime = monotonic_ns() / 1000;
  c.seq = seq;
  c.command = cmd;
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "pcisim-soak-console: an instructor's console for scripts/soak. Keeps fluoroscopy on, moves the "
      "C-arm, injects contrast and reloads the scene on a schedule; checks every force command is finite "
      "and within the peak; counts the frames it receives. Writes a JSON summary."};
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0",
              image_url = "udpm://239.255.76.67:7668?ttl=0&recv_buf_size=4194304";
  std::string scene_path, out_path;
  double seconds = 60, carm_every_s = 5, contrast_every_s = 20, reload_every_s = 120;
  uint32_t seed = 1;
  Watch w;
  app.add_option("--lcm-url", lcm_url, "control LCM URL")->capture_default_str();
  app.add_option("--lcm-image-url", image_url, "image LCM URL")->capture_default_str();
  app.add_option("--seconds", seconds, "how long to run")->check(CLI::Range(1.0, 1e6))->capture_default_str();
  app.add_option("--scene", scene_path, "scene file to reload on the schedule (absolute path); none: no reloads");
  app.add_option("--carm-every-s", carm_every_s, "C-arm move period")
      ->check(CLI::Range(0.1, 1e6))
      ->capture_default_str();
  app.add_option("--contrast-every-s", contrast_every_s, "contrast injection period")
      ->check(CLI::Range(0.1, 1e6))
      ->capture_default_str();
  app.add_option("--reload-every-s", reload_every_s, "scene reload period")
      ->check(CLI::Range(1.0, 1e6))
      ->capture_default_str();
  app.add_option("--peak-force-n", w.peak_force_n, "the scene's haptics.peak_force_n")->capture_default_str();
  app.add_option("--peak-torque-nmm", w.peak_torque_nmm, "the scene's haptics.peak_torque_nm, in N mm")
      ->capture_default_str();
  app.add_option("--seed", seed, "random C-arm angles")->capture_default_str();
  app.add_option("--out", out_path, "JSON summary file")->required();
  CLI11_PARSE(app, argc, argv);

  lcm::LCM control(lcm_url), images(image_url);
  if (!control.good() || !images.good()) {
    std::cerr << "pcisim-soak-console: cannot open LCM (" << lcm_url << ", " << image_url << ")\n";
    return 3;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  control.subscribe(pcisim::protocol::kForceChannel, &Watch::on_force, &w);
  control.subscribe(pcisim::protocol::kStatusChannel, &Watch::on_status, &w);
  images.subscribe(pcisim::protocol::kXrayChannel, &Watch::on_frame, &w);
  std::thread image_rx([&] {
    while (!g_stop) images.handleTimeout(20);
  });

  using C = pcisim_lcm::session_command_t;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> primary(-60, 60), secondary(-30, 30);
  int64_t seq = 0, carm_moves = 0, injections = 0, reloads = 0, pedal_presses = 0;
  const int64_t t0 = monotonic_ns();
  auto due = [&](double period_s, double& next_s, double now_s) {
    if (now_s < next_s) return false;
    next_s += period_s;
    return true;
  };
  double next_carm = carm_every_s, next_contrast = contrast_every_s, next_reload = reload_every_s, next_pedal = 0;
  while (!g_stop) {
    control.handleTimeout(20);
    const double now_s = (monotonic_ns() - t0) * 1e-9;
    if (now_s >= seconds) break;
    // the pedal is pressed again each second: a reloaded pipeline starts with the beam off
    if (due(1.0, next_pedal, now_s)) {
      auto c = command(C::CMD_FLUORO_PEDAL, seq++);
      c.pedal_down = 1;
      control.publish(pcisim::protocol::kSessionChannel, &c);
      ++pedal_presses;
    }
    if (due(carm_every_s, next_carm, now_s)) {
      auto c = command(C::CMD_CARM, seq++);
      c.primary_angle_deg = primary(rng);
      c.secondary_angle_deg = secondary(rng);
      control.publish(pcisim::protocol::kSessionChannel, &c);
      ++carm_moves;
    }
    if (due(contrast_every_s, next_contrast, now_s)) {
      auto c = command(C::CMD_CONTRAST, seq++);
      control.publish(pcisim::protocol::kSessionChannel, &c);
      ++injections;
    }
    if (!scene_path.empty() && due(reload_every_s, next_reload, now_s)) {
      auto c = command(C::CMD_LOAD_SCENE, seq++);
      c.scene_path = scene_path;
      control.publish(pcisim::protocol::kSessionChannel, &c);
      ++reloads;
    }
  }
  g_stop = true;
  image_rx.join();

  nlohmann::json j = {{"seconds", (monotonic_ns() - t0) * 1e-9},
                      {"sent",
                       {{"pedal_presses", pedal_presses},
                        {"carm_moves", carm_moves},
                        {"injections", injections},
                        {"reloads", reloads}}},
                      {"forces",
                       {{"received", w.forces},
                        {"undecodable", w.forces_bad},
                        {"non_finite", w.forces_non_finite},
                        {"over_peak", w.forces_over_peak},
                        {"max_abs_force_n", w.max_abs_force_n},
                        {"max_abs_torque_nmm", w.max_abs_torque_nmm},
                        {"peak_force_n", w.peak_force_n}}},
                      {"frames", {{"received", w.frames_received}, {"undecodable", w.frames_bad}}},
                      {"status", {{"received", w.statuses}, {"undecodable", w.status_bad}, {"last", w.last_status}}}};
  std::ofstream out(out_path);
  out << j.dump(2) << "\n";
  if (!out.flush()) {
    std::cerr << "pcisim-soak-console: cannot write " << out_path << "\n";
    return 1;
  }
  std::cout << j.dump() << "\n";
  return 0;
}
