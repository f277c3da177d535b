// pcisim-bridge: the instrument bridge. Turns an instrument (a scripted trainee, a recorded
// session, an encoder box on a serial port or a Linux force-feedback device) into instrument_state_t at 1 kHz and logs
// the force_command_t the server sends back (the force it would render); or, with --probe-script, a scripted ultrasound
// probe into probe_state_t.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <nlohmann/json.hpp>
#include <fstream>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <spdlog/spdlog.h>

#include "clients/bridge/bridge.h"
#include "clients/bridge/device_profile.h"
#include "clients/bridge/evdev_device.h"
#include "clients/bridge/replay_device.h"
#include "clients/bridge/serial_device.h"
#include "protocol/channels.h"
#include "realtime/stop_signal.h"

int main(int argc, char** argv) {
  using namespace pcisim::clients;
  CLI::App app{
      "pcisim-bridge: turns an instrument into instrument_state_t at 1 kHz for pcisim-server and logs "
      "the force_command_t it sends back. Devices: scripted (a trainee script, docs/trainee-script.md), "
      "replay (an lcm-logger log of a session, docs/recording.md), serial (an encoder box, "
      "docs/serial-protocol.md), evdev (a force-feedback wheel or joystick: its axes in, the torque out as a "
      "constant effect; docs/serial-protocol.md, \"A force-feedback device\"). With --probe-script it publishes a "
      "scripted ultrasound probe's "
      "probe_state_t on PCISIM_PROBE instead (docs/trainee-script.md, \"Probe script\")."};
  std::string device = "scripted", script_path, probe_script_path, log_path, port, stats_path, profile_path, event_path;
  std::string insertion_axis = "ABS_Y", rotation_axis = "ABS_X", keys = "BTN_0,BTN_1,BTN_2";
  EvdevConfig evdev;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string replay_channel = pcisim::protocol::kInstrumentChannel;
  double duration_s = 0, wait_for_server_s = 0, speed = 1.0;
  BridgeOptions options;
  SerialCalibration cal;
  int baud = 115200;
  bool print_script = false, print_probe_script = false, print_profile = false;
  auto* device_opt = app.add_option("--device", device, "instrument source")
                         ->check(CLI::IsMember({"scripted", "replay", "serial", "evdev"}))
                         ->capture_default_str();
  auto* script_opt =
      app.add_option("--script", script_path, "scripted: trainee script (JSON); default: the built-in one");
  auto* log_opt = app.add_option("--log", log_path, "replay: lcm-logger file of a recorded session");
  app.add_option("--speed", speed, "replay: 1 = real time, 2 = twice as fast, 0 = stepped (one sample per tick)")
      ->check(CLI::Range(0.0, 100.0))
      ->capture_default_str();
  app.add_option("--replay-channel", replay_channel, "replay: channel of the recorded instrument")
      ->capture_default_str();
  auto* port_opt = app.add_option("--port", port, "serial: the serial port or pseudo-terminal, e.g. /dev/ttyUSB0");
  app.add_option("--baud", baud, "serial: baud rate")->capture_default_str();
  auto* event_opt = app.add_option("--event", event_path, "evdev: the device's event node, e.g. /dev/input/event5");
  std::vector<CLI::Option*> evdev_opts = {
      app.add_option("--insertion-axis", insertion_axis,
                     "evdev: the absolute axis whose whole travel is the insertion range (a pedal: ABS_Z, ABS_GAS, "
                     "ABS_BRAKE; a stick: ABS_Y), by name or number")
          ->capture_default_str(),
      app.add_option("--rotation-axis", rotation_axis, "evdev: the wheel's axis (its middle is 0)")
          ->capture_default_str(),
      app.add_option("--wheel-range-deg", evdev.wheel_range_deg,
                     "evdev: the wheel's lock-to-lock turn (negative flips it)")
          ->capture_default_str(),
      app.add_option("--full-scale-nmm", evdev.full_scale_torque_nmm,
                     "evdev: the torque (N mm) rendered at the device's strongest: the server's peak by default")
          ->capture_default_str(),
      app.add_option("--ff-gain", evdev.gain, "evdev: the device's force-feedback gain, (0, 1]")->capture_default_str(),
      app.add_option("--keys", keys,
                     "evdev: the keys of the fluoroscopy pedal, the cine pedal and the contrast button, by name "
                     "(BTN_0, BTN_TRIGGER, ...), number, or none")
          ->capture_default_str()};
  auto* profile_opt = app.add_option("--profile", profile_path,
                                     "serial: the instrument box's profile (JSON: encoder scales and signs, insertion "
                                     "range, silent timeout, force scale, limits and filter; docs/serial-protocol.md); "
                                     "--print-profile shows the default");
  std::vector<CLI::Option*> cal_opts = {
      app.add_option("--mm-per-count", cal.mm_per_count, "serial: insertion encoder calibration")
          ->capture_default_str(),
      app.add_option("--rad-per-count", cal.rad_per_count, "serial: rotation encoder calibration")
          ->capture_default_str(),
      app.add_option("--zero-counts", cal.insertion_zero_counts, "serial: insertion counts at 0 mm")
          ->capture_default_str(),
      app.add_option("--max-insertion-mm", cal.max_insertion_mm,
                     "serial: insertion limit; evdev: the insertion at the axis's far end")
          ->capture_default_str()};
  for (CLI::Option* c : cal_opts) profile_opt->excludes(c);
  // a probe bridge has no instrument: the probe replaces the device
  app.add_option("--probe-script", probe_script_path,
                 "publish probe_state_t on PCISIM_PROBE from a probe script (JSON, FILE) or 'builtin' (a press on "
                 "the kidney phantom) instead of an instrument's instrument_state_t")
      ->excludes(device_opt, script_opt, log_opt, port_opt, event_opt);
  app.add_option("--lcm-url", lcm_url, "LCM URL shared with the server")->capture_default_str();
  app.add_option("--duration", duration_s, "seconds to run; 0 = until SIGINT/SIGTERM (or the end of a replay)")
      ->check(CLI::Range(0.0, 1e7));
  app.add_option("--wait-for-server", wait_for_server_s,
                 "hold the device at t=0 until the server answers (up to S seconds)")
      ->check(CLI::Range(0.0, 600.0));
  app.add_option("--rate-hz", options.rate_hz, "publish rate")->check(CLI::Range(1.0, 10000.0))->capture_default_str();
  app.add_option("--device-id", options.device_id, "device_id of the messages published")->capture_default_str();
  app.add_option("--stats-json", stats_path,
                 "write the run's figures at exit: samples, force lines, and the end-to-end latency histograms' "
                 "percentiles (sample -> force back, -> device write, the write itself)");
  app.add_flag("--print-script", print_script, "print the built-in trainee script and exit");
  app.add_flag("--print-profile", print_profile, "print the default instrument box profile and exit");
  app.add_flag("--print-probe-script", print_probe_script, "print the built-in probe script and exit");
  CLI11_PARSE(app, argc, argv);
  // until it runs, SIGINT/SIGTERM end it at once, saying so
  pcisim::realtime::install_stop_signals("pcisim-bridge");

  if (print_script || print_probe_script || print_profile) {
    if (print_script) std::cout << TraineeScript::builtin_text();
    if (print_probe_script) std::cout << ProbeScript::builtin_text();
    if (print_profile) std::cout << default_device_profile_text() << "\n";
    return 0;
  }
  std::unique_ptr<InstrumentDevice> dev;
  std::optional<ProbeScript> probe;
  try {
    if (!profile_path.empty() && ((device != "serial" && device != "evdev") || !probe_script_path.empty()))
      throw std::runtime_error("--profile describes an instrument: it needs --device serial or evdev");
    if (device != "evdev" && (!event_path.empty() || std::any_of(evdev_opts.begin(), evdev_opts.end(),
                                                                 [](CLI::Option* o) { return o->count() > 0; })))
      throw std::runtime_error("--event and the evdev options need --device evdev");
    DeviceProfile profile;
    if (!profile_path.empty()) {
      profile = load_device_profile(profile_path);
      cal = profile.calibration;
      options.force_shaping = profile.force;
      spdlog::info("bridge: instrument profile '{}' from {}", profile.name, profile_path);
    }
    if (!probe_script_path.empty()) {
      probe = probe_script_path == "builtin" ? ProbeScript::parse(ProbeScript::builtin_text(), "built-in")
                                             : ProbeScript::load(probe_script_path);
    } else if (device == "scripted") {
      dev = std::make_unique<ScriptedDevice>(script_path.empty()
                                                 ? TraineeScript::parse(TraineeScript::builtin_text(), "built-in")
                                                 : TraineeScript::load(script_path));
    } else if (device == "replay") {
      if (log_path.empty()) throw std::runtime_error("--device replay needs --log FILE");
      dev = std::make_unique<ReplayDevice>(log_path, speed, replay_channel);
    } else if (device == "evdev") {
      if (event_path.empty()) throw std::runtime_error("--device evdev needs --event /dev/input/eventN");
      evdev.insertion_axis = evdev_axis_code(insertion_axis);
      evdev.rotation_axis = evdev_axis_code(rotation_axis);
      if (evdev.insertion_axis < 0) throw std::runtime_error("--insertion-axis: unknown axis '" + insertion_axis + "'");
      if (evdev.rotation_axis < 0) throw std::runtime_error("--rotation-axis: unknown axis '" + rotation_axis + "'");
      int* key_slots[] = {&evdev.fluoro_key, &evdev.cine_key, &evdev.contrast_key};
      std::vector<std::string> names = CLI::detail::split(keys, ',');
      if (names.size() != 3) throw std::runtime_error("--keys: three keys (fluoro,cine,contrast), got '" + keys + "'");
      for (size_t i = 0; i < 3; ++i) {
        *key_slots[i] = evdev_key_code(names[i]);
        if (*key_slots[i] < 0 && names[i] != "none") throw std::runtime_error("--keys: unknown key '" + names[i] + "'");
      }
      evdev.min_insertion_mm = cal.min_insertion_mm;
      evdev.max_insertion_mm = cal.max_insertion_mm;
      dev = std::make_unique<EvdevDevice>(event_path, evdev);
    } else {
      if (port.empty()) throw std::runtime_error("--device serial needs --port PATH");
      dev = std::make_unique<SerialDevice>(port, baud, cal);
    }
  } catch (const std::exception& e) {
    std::cerr << "pcisim-bridge: " << e.what() << "\n";
    return 2;
  }
  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) {
    std::cerr << "pcisim-bridge: cannot open LCM at " << lcm_url << "\n";
    return 3;
  }
  pcisim::realtime::mark_running();  // from now SIGINT/SIGTERM stop the loop cleanly
  options.duration_s = duration_s;
  options.wait_for_server_s = wait_for_server_s;
  const std::string source =
      probe ? fmt::format("scripted probe '{}' ({:.1f} s)", probe->name(), probe->duration_s()) : dev->describe();
  spdlog::info("bridge: {}, publishing at {} Hz on {}", source, options.rate_hz, lcm_url);
  Bridge bridge = probe ? Bridge(lcm, *probe, options) : Bridge(lcm, *dev, options);
  const BridgeStats s = bridge.run(pcisim::realtime::stop_flag());
  std::string extra;
  if (auto* serial = dynamic_cast<SerialDevice*>(dev.get()))
    extra = fmt::format(", serial lines {} ok / {} malformed{}, force lines {} sent / {} dropped", serial->lines(),
                        serial->malformed(), serial->unplugged() ? ", unplugged" : "", serial->force_lines(),
                        serial->force_lines_dropped());
  if (auto* ff = dynamic_cast<EvdevDevice*>(dev.get()))
    extra = fmt::format(", force-feedback effect uploaded {} times, its spring {} times, {} writes refused{}",
                        ff->uploads(), ff->spring_uploads(), ff->failed_writes(), ff->unplugged() ? ", unplugged" : "");
  if (!probe) {
    extra += s.force_zeroed > 0
                 ? fmt::format(", force zero in {} ticks (last: {})", s.force_zeroed, describe(s.force_state))
                 : std::string(", force never zeroed");
    auto figures = [](const LatencyHistogram& h) {
      return fmt::format("p50 {:.2f} / p99 {:.2f} / p99.9 {:.2f} / max {:.2f} ms over {}", h.percentile_us(0.5) * 1e-3,
                         h.percentile_us(0.99) * 1e-3, h.percentile_us(0.999) * 1e-3, h.max_us() * 1e-3, h.count());
    };
    extra += fmt::format("; latency sample -> force back {}", figures(s.sample_to_force));
    if (s.sample_to_device.count() > 0)
      extra += fmt::format(", -> device write (the next tick's) {}; the write itself {}", figures(s.sample_to_device),
                           figures(s.device_write));
  }
  if (!stats_path.empty()) {
    auto figures = [](const LatencyHistogram& h) {
      return nlohmann::json{{"p50", h.percentile_us(0.5)},
                            {"p99", h.percentile_us(0.99)},
                            {"p999", h.percentile_us(0.999)},
                            {"max", h.max_us()},
                            {"count", h.count()}};
    };
    nlohmann::json j = {{"published", s.published},
                        {"fault_samples", s.fault_samples},
                        {"missed_periods", s.missed_periods},
                        {"forces_received", s.forces_received},
                        {"forces_bad", s.forces_bad},
                        {"force_rendered", s.force_rendered},
                        {"force_zeroed", s.force_zeroed},
                        {"sample_to_force_us", figures(s.sample_to_force)},
                        {"sample_to_device_us", figures(s.sample_to_device)},
                        {"device_write_us", figures(s.device_write)}};
    if (auto* serial = dynamic_cast<SerialDevice*>(dev.get())) {
      j["force_lines"] = serial->force_lines();
      j["force_lines_dropped"] = serial->force_lines_dropped();
    }
    std::ofstream out(stats_path);
    out << j.dump(2) << "\n";
    if (!out) {
      std::cerr << "pcisim-bridge: " << stats_path << ": cannot write the stats\n";
      return 1;
    }
  }
  spdlog::info(
      "bridge: done, {} samples published ({:.0f} Hz, {} in fault, {} periods missed), {} force commands "
      "received, {} bad{}",
      s.published, s.elapsed_s > 0 ? (s.published - 1) / s.elapsed_s : 0.0, s.fault_samples, s.missed_periods,
      s.forces_received, s.forces_bad, extra);
  return 0;
}
