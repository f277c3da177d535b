// pcisim-box-sim: an instrument box on a pseudo-terminal, for closing the haptic loop without
// hardware (scripts/main-job with PCISIM_MAIN_JOB_DEVICE=box): sends a trainee script's motion as
// encoder lines and applies the force lines the bridge sends back, with the box's 50 ms watchdog
// (docs/serial-protocol.md). Writes every force line it applied to a CSV and a closing summary.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>

#include "clients/bridge/box_simulator.h"
#include "realtime/clock.h"
#include "realtime/stop_signal.h"

int main(int argc, char** argv) {
  using namespace pcisim::clients;
  CLI::App app{
      "pcisim-box-sim: an instrument box on a pseudo-terminal. It sends a trainee script's insertion and "
      "rotation as encoder lines (E ...) and applies the force lines (F ...) pcisim-bridge --device serial "
      "sends back, zeroing the force when none came for 50 ms (its watchdog); docs/serial-protocol.md. "
      "Give the bridge --port LINK."};
  std::string link, script_path, log_path;
  double duration_s = 0, rate_hz = 1000;
  bool hold = false;
  SerialCalibration cal;
  app.add_option("--link", link, "make LINK a symbolic link to the pseudo-terminal (the bridge's --port)")->required();
  app.add_option("--script", script_path, "trainee script (JSON, docs/trainee-script.md); default: the built-in one");
  app.add_option("--log", log_path, "write every force line received as CSV (t_s, axial_mN, torque_uNm, seq)");
  app.add_option("--duration", duration_s,
                 "seconds to run; 0 = until SIGINT/SIGTERM. With --hold-until-force, seconds of script from its t=0 "
                 "(as the bridge's --duration counts from the server's answer), or of waiting while it holds")
      ->check(CLI::Range(0.0, 1e7));
  app.add_option("--rate-hz", rate_hz, "encoder lines per second")
      ->check(CLI::Range(1.0, 10000.0))
      ->capture_default_str();
  app.add_flag("--hold-until-force", hold,
               "hold the script at t=0 until the first force line (the bridge sends its first once the server "
               "answers), so box and bridge start together");
  app.add_option("--mm-per-count", cal.mm_per_count, "insertion encoder calibration (give the bridge the same)")
      ->capture_default_str();
  app.add_option("--rad-per-count", cal.rad_per_count, "rotation encoder calibration")->capture_default_str();
  app.add_option("--zero-counts", cal.insertion_zero_counts, "insertion counts at 0 mm")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  pcisim::realtime::install_stop_signals("pcisim-box-sim");

  std::unique_ptr<BoxSimulator> box;
  try {
    TraineeScript script = script_path.empty() ? TraineeScript::parse(TraineeScript::builtin_text(), "built-in")
                                               : TraineeScript::load(script_path);
    box = std::make_unique<BoxSimulator>(std::move(script), cal);
    // the link: replaced when it is a link, refused when it is anything else
    struct stat st {};
    if (::lstat(link.c_str(), &st) == 0) {
      if (!S_ISLNK(st.st_mode)) throw std::runtime_error(link + ": exists and is not a symbolic link; not replaced");
      ::unlink(link.c_str());
    }
    if (::symlink(box->port().c_str(), link.c_str()) != 0)
      throw std::runtime_error(fmt::format("{}: cannot link to {}: {}", link, box->port(), std::strerror(errno)));
  } catch (const std::exception& e) {
    std::cerr << "pcisim-box-sim: " << e.what() << "\n";
    return 2;
  }
  std::printf("box-sim: %s -> %s, encoder lines at %.0f Hz%s\n", link.c_str(), box->port().c_str(), rate_hz,
              hold ? ", holding t=0 until the first force line" : "");
  std::fflush(stdout);

  pcisim::realtime::mark_running();
  const auto period_ns = static_cast<int64_t>(1e9 / rate_hz);
  const int64_t start_ns = pcisim::realtime::monotonic_ns();
  int64_t script_start_ns = hold ? -1 : start_ns;
  double tripped_s = 0, most_axial_n = 0, most_torque_nmm = 0, t_s = 0;
  int64_t trips = 0;
  bool was_tripped = true;
  for (int64_t tick = 0; !pcisim::realtime::stop_flag(); ++tick) {
    const int64_t now_ns = pcisim::realtime::monotonic_ns();
    if (script_start_ns < 0 && box->force_lines() > 0) script_start_ns = now_ns;
    t_s = script_start_ns < 0 ? 0.0 : (now_ns - script_start_ns) * 1e-9;
    const double wall_s = (now_ns - start_ns) * 1e-9;
    // the duration is the script's once it runs (a slow server's start does not shorten it)
    if (duration_s > 0 && (script_start_ns < 0 ? wall_s : t_s) >= duration_s) break;
    box->step(t_s);
    // the watchdog on the box's own clock (wall time: it runs while the script holds)
    const bool tripped = box->watchdog_tripped(t_s) && script_start_ns >= 0;
    if (tripped && !was_tripped) ++trips;
    was_tripped = tripped;
    if (tripped) tripped_s += period_ns * 1e-9;
    most_axial_n = std::max(most_axial_n, std::abs(box->applied_axial_n(t_s)));
    most_torque_nmm = std::max(most_torque_nmm, std::abs(box->applied_torque_nmm(t_s)));
    pcisim::realtime::sleep_until_ns(start_ns + (tick + 1) * period_ns);
  }
  pcisim::realtime::mark_stopped();
  ::unlink(link.c_str());
  if (!log_path.empty()) {
    try {
      box->write_csv(log_path);
    } catch (const std::exception& e) {
      std::cerr << "pcisim-box-sim: " << e.what() << "\n";
      return 1;
    }
  }
  std::printf(
      "box-sim: done after %.1f s of script, %lld encoder lines sent, %lld force lines applied (%lld malformed), "
      "largest %.3f N and %.3f N mm, watchdog tripped %lld times (%.2f s at zero)%s%s; the script's t=0 at "
      "CLOCK_MONOTONIC %.6f s\n",
      t_s, static_cast<long long>(box->lines_sent()), static_cast<long long>(box->force_lines()),
      static_cast<long long>(box->malformed()), most_axial_n, most_torque_nmm, static_cast<long long>(trips), tripped_s,
      log_path.empty() ? "" : ", log ", log_path.c_str(), script_start_ns * 1e-9);
  return 0;
}
