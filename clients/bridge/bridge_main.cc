// pcisim-bridge: the instrument bridge. Publishes instrument_state_t at 1 kHz from a device
// (this build: the scripted trainee) and logs the force commands the server returns.
#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>
#include <thread>

#include "clients/bridge/trainee_script.h"
#include "pcisim_lcm/force_command_t.hpp"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "server/realtime/clock.h"
#include "server/realtime/deadline_schedule.h"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

struct ForceLog {
  std::atomic<int64_t> received{0}, bad{0};
  std::atomic<double> last_force_n{0}, last_torque_nmm{0};
  std::atomic<int32_t> last_flags{0};
  pcisim_lcm::force_command_t msg{};
  void on_force(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (!pcisim::protocol::decode_checked(*rbuf, msg)) {
      ++bad;
      return;
    }
    ++received;
    last_force_n = msg.axial_force_n;
    last_torque_nmm = msg.torque_nmm;
    last_flags = msg.flags;
  }
};

}  // namespace

int main(int argc, char** argv) {
  using namespace pcisim;
  CLI::App app{"pcisim-bridge: turns an instrument into instrument_state_t at 1 kHz and renders the "
               "force_command_t the server sends back (this build logs it)."};
  std::string device = "scripted", script_path, lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  double duration_s = 0, rate_hz = 1000;
  int device_id = 1;
  app.add_option("--device", device, "instrument source")->check(CLI::IsMember({"scripted"}))->capture_default_str();
  app.add_option("--script", script_path, "trainee script (JSON); default: the built-in one (docs/trainee-script.md)");
  app.add_option("--lcm-url", lcm_url, "LCM URL shared with the server")->capture_default_str();
  app.add_option("--duration", duration_s, "seconds to run; 0 = until SIGINT/SIGTERM")->check(CLI::Range(0.0, 1e7));
  app.add_option("--rate-hz", rate_hz, "publish rate")->check(CLI::Range(1.0, 10000.0))->capture_default_str();
  app.add_option("--device-id", device_id, "instrument_state_t.device_id")->capture_default_str();
  double wait_for_server_s = 0;
  app.add_option("--wait-for-server", wait_for_server_s,
                 "hold the script at t=0 until the server answers (up to this many seconds)")
      ->check(CLI::Range(0.0, 600.0));
  bool print_script = false;
  app.add_flag("--print-script", print_script, "print the built-in trainee script and exit");
  CLI11_PARSE(app, argc, argv);

  if (print_script) {
    std::cout << clients::TraineeScript::builtin_text();
    return 0;
  }
  clients::TraineeScript script;
  try {
    script = script_path.empty() ? clients::TraineeScript::parse(clients::TraineeScript::builtin_text(), "built-in")
                                 : clients::TraineeScript::load(script_path);
  } catch (const std::exception& e) {
    std::cerr << "pcisim-bridge: " << e.what() << "\n";
    return 2;
  }
  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) {
    std::cerr << "pcisim-bridge: cannot open LCM at " << lcm_url << "\n";
    return 3;
  }
  ForceLog forces;
  lcm.subscribe(protocol::kForceChannel, &ForceLog::on_force, &forces);
  std::thread rx([&] {
    while (!g_stop) lcm.handleTimeout(20);
  });
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  spdlog::info("bridge: script '{}' ({:.1f} s), publishing at {} Hz on {}", script.name(), script.duration_s(),
               rate_hz, lcm_url);

  // absolute-deadline publishing, as the haptic loop does
  pcisim_lcm::instrument_state_t m{};
  m.device_id = device_id;
  m.status = pcisim_lcm::instrument_state_t::STATUS_OK;
  const auto period_ns = static_cast<int64_t>(1e9 / rate_hz);
  int64_t start_ns = server::monotonic_ns();
  bool waiting = wait_for_server_s > 0;
  server::DeadlineSchedule schedule(start_ns, period_ns);
  int64_t next_log_ns = start_ns + 1'000'000'000;
  for (int64_t seq = 0; !g_stop; ++seq) {
    const int64_t now_ns = server::monotonic_ns();
    if (waiting && (forces.received > 0 || (now_ns - start_ns) * 1e-9 > wait_for_server_s)) {
      waiting = false;
      if (forces.received == 0) spdlog::warn("bridge: no answer from the server after {} s, starting anyway", wait_for_server_s);
      start_ns = now_ns;  // the script's clock starts now
      next_log_ns = now_ns + 1'000'000'000;
    }
    const double t_s = waiting ? 0.0 : (now_ns - start_ns) * 1e-9;
    if (duration_s > 0 && t_s >= duration_s) break;
    const auto r = script.sample(t_s);
    m.utime = now_ns / 1000;
    m.seq = seq;
    m.buttons = r.buttons;
    m.insertion_mm = r.insertion_mm;
    m.rotation_rad = r.rotation_rad;
    m.insertion_rate_mm_s = r.insertion_rate_mm_s;
    m.rotation_rate_rad_s = r.rotation_rate_rad_s;
    lcm.publish(protocol::kInstrumentChannel, &m);
    if (!waiting && now_ns >= next_log_ns) {
      next_log_ns += 1'000'000'000;
      spdlog::info("bridge: t={:5.1f}s insertion {:6.1f} mm rotation {:6.2f} rad buttons {:#x} | force {:+.3f} N "
                   "torque {:+.3f} N·mm flags {:#x} ({} commands)",
                   t_s, r.insertion_mm, r.rotation_rad, r.buttons, forces.last_force_n.load(),
                   forces.last_torque_nmm.load(), forces.last_flags.load(), forces.received.load());
    }
    server::sleep_until_ns(schedule.deadline_ns());
    schedule.complete(server::monotonic_ns());
  }
  g_stop = true;
  rx.join();
  spdlog::info("bridge: done, {} force commands received, {} bad", forces.received.load(), forces.bad.load());
  return 0;
}
