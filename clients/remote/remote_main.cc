// pcisim-remote: watch and steer a pcisim session from a browser. Subscribes to the server's LCM
// channels and serves a page plus a WebSocket endpoint (docs/remote.md).
#include <CLI/CLI.hpp>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <thread>

#include "clients/remote/gateway.h"
#include "realtime/stop_signal.h"

int main(int argc, char** argv) {
  using namespace pcisim::remote;
  CLI::App app{
      "pcisim-remote: a web gateway to a running pcisim-server. It shows the live fluoroscopy (or, in a soft-tissue "
      "scene, the ultrasound image), the wire and "
      "session state (C-arm angles, fluoroscopy time, contrast used) and the loop health in a browser, and lets a "
      "controller work the pedal, cine, C-arm, contrast, reset and pause, and drive the wire with the arrow keys.\n\n"
      "Access: at start it prints two random tokens, observer (watch only) and controller (watch and control), "
      "and the URLs to open (http://HOST:PORT/#token=TOKEN). A WebSocket without a valid token is refused (401 "
      "missing, 403 wrong); commands from observers are refused; commands are range-checked and rate-limited per "
      "connection. It listens on 127.0.0.1 only unless --bind says otherwise; anyone who can reach the port and "
      "holds a token gets in, so share tokens as you would a password. Protocol and limits: docs/remote.md."};
  GatewayOptions o;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string image_url = "udpm://239.255.76.67:7668?ttl=0&recv_buf_size=4194304";
  std::string token_file, format = "jpeg", log_level = "info";
  bool no_keyboard = false;
  std::vector<int> window;
  app.add_option("--bind", o.bind, "address to listen on (0.0.0.0: every interface)")->capture_default_str();
  app.add_option("--port", o.port, "TCP port; 0 picks a free one (printed)")->capture_default_str();
  app.add_option("--token-file", token_file,
                 "also write port=, observer= and controller= lines to this file (mode 0600)");
  app.add_option("--lcm-url", lcm_url, "LCM URL of the server's control traffic")->capture_default_str();
  app.add_option("--lcm-image-url", image_url, "LCM URL of the X-ray and ultrasound frames")->capture_default_str();
  app.add_option("--format", format, "image format sent to browsers")
      ->check(CLI::IsMember({"jpeg", "png"}))
      ->capture_default_str();
  app.add_option("--jpeg-quality", o.encoder.jpeg_quality, "JPEG quality")
      ->check(CLI::Range(10, 100))
      ->capture_default_str();
  app.add_option("--window", window,
                 "display window LO HI: 16-bit X-ray values mapped to black and white (default 0 65535; ultrasound "
                 "frames are 8-bit and shown as they come)")
      ->expected(2)
      ->check(CLI::Range(0, 65535));
  app.add_option("--max-fps", o.hub.max_fps, "most frames per second per connection (a page may ask for fewer)")
      ->check(CLI::Range(0.5, 60.0))
      ->capture_default_str();
  app.add_option("--max-clients", o.hub.max_clients, "most WebSocket connections at once")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--command-rate", o.hub.command_rate, "session commands per second per connection (token bucket rate)")
      ->check(CLI::Range(0.1, 100.0))
      ->capture_default_str();
  app.add_option("--command-burst", o.hub.command_burst, "token bucket size for session commands")
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
  app.add_option("--injection-ml", o.tracker.injection_ml,
                 "contrast volume of one injection seen on the bus before the server's next status reports it (the "
                 "scene's contrast.injection_ml)")
      ->check(CLI::Range(0.5, 30.0))
      ->capture_default_str();
  app.add_flag("--no-keyboard-instrument", no_keyboard, "do not offer the keyboard instrument");
  app.add_option("--keyboard-device-id", o.keyboard.device_id,
                 "instrument_state_t.device_id of the keyboard instrument")
      ->capture_default_str();
  app.add_option("--keyboard-rate-hz", o.keyboard.rate_hz, "publish rate of the keyboard instrument")
      ->check(CLI::Range(50.0, 2000.0))
      ->capture_default_str();
  app.add_option("--keyboard-insert-mm-s", o.keyboard.insert_mm_s, "insertion speed of a held arrow key")
      ->check(CLI::Range(0.1, 200.0))
      ->capture_default_str();
  app.add_option("--keyboard-rotate-rad-s", o.keyboard.rotate_rad_s, "rotation speed of a held arrow key")
      ->check(CLI::Range(0.01, 20.0))
      ->capture_default_str();
  app.add_option("--debrief-html", o.debrief_html,
                 "the server's debrief page (its --debrief-html) on this host: served at /debrief.html to pages "
                 "with a token, linked from the page's debrief card");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}))
      ->capture_default_str();
  app.footer(
      "The keyboard instrument publishes instrument_state_t (device id above) only while a controller page has "
      "enabled it and no other instrument is heard on the bus; hardware always wins. Pedals a page holds down "
      "are released when it disconnects. SIGINT/SIGTERM close every connection and exit.");
  CLI11_PARSE(app, argc, argv);
  // until it runs, SIGINT/SIGTERM end it at once, saying so
  pcisim::realtime::install_stop_signals("pcisim-remote");
  spdlog::set_level(spdlog::level::from_str(log_level));
  o.encoder.format = format == "png" ? ImageFormat::kPng : ImageFormat::kJpeg;
  if (window.size() == 2) {
    if (window[1] <= window[0]) {
      std::cerr << "pcisim-remote: --window: HI must exceed LO\n";
      return 2;
    }
    o.encoder.window_lo = window[0];
    o.encoder.window_hi = window[1];
  }
  o.keyboard_instrument = !no_keyboard;
  o.commands.default_contrast_ml = o.tracker.injection_ml;

  lcm::LCM control(lcm_url), images(image_url);
  if (!control.good() || !images.good()) {
    std::cerr << "pcisim-remote: cannot open LCM at " << (control.good() ? image_url : lcm_url)
              << " (for udpm, is there a multicast route? see docs/protocol.md)\n";
    return 3;
  }
  pcisim::realtime::mark_running();  // from now SIGINT/SIGTERM stop the loop cleanly
  std::signal(SIGPIPE, SIG_IGN);
  Gateway gateway(o, control, images, AccessTokens());
  try {
    gateway.start();
  } catch (const std::exception& e) {
    std::cerr << "pcisim-remote: " << e.what() << "\n";
    return 4;
  }
  const std::string host = o.bind == "0.0.0.0" ? "HOST" : o.bind;
  const std::string base = "http://" + host + ":" + std::to_string(gateway.port()) + "/";
  std::cout << "pcisim-remote: serving " << base << " (frames from " << image_url << ")\n"
            << "  controller: " << base << "#token=" << gateway.tokens().controller() << "\n"
            << "  observer:   " << base << "#token=" << gateway.tokens().observer() << "\n"
            << std::flush;
  if (!token_file.empty()) {
    // written whole and renamed into place: a reader never sees half a file
    const mode_t old = umask(077);
    std::ofstream f(token_file + ".tmp");
    f << "port=" << gateway.port() << "\nobserver=" << gateway.tokens().observer()
      << "\ncontroller=" << gateway.tokens().controller() << "\n";
    umask(old);
    std::error_code ec;
    if (!f.flush() || (f.close(), std::filesystem::rename(token_file + ".tmp", token_file, ec), ec)) {
      std::cerr << "pcisim-remote: cannot write " << token_file << "\n";
      return 1;
    }
  }
  while (!pcisim::realtime::stop_flag()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  spdlog::info("remote: stopping");
  gateway.stop();
  const auto s = gateway.hub_stats();
  const auto c = gateway.counters();
  spdlog::info(
      "remote: done: {} connections, {} X-ray and {} ultrasound frames received, {} encoded, {} sent, {} dropped for "
      "slow pages, {} commands forwarded, {} refused, {} rate-limited, {} bad X-ray and {} bad ultrasound frames, {} "
      "bad control messages",
      s.connections_total, c.frames_received, c.ultrasound_received, c.frames_encoded, s.frames_sent, s.frames_dropped,
      s.commands_forwarded, s.commands_refused, s.rate_limited, c.frames_bad, c.ultrasound_bad, c.control_bad);
  return 0;
}
