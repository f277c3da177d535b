#include "server/session_runner.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <functional>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "realtime/stop_signal.h"
#include "server/case_builder.h"
#include "server/server.h"

namespace pcisim::server {

StatsReport run_session(Scene scene, lcm::LCM& control, const SessionOptions& options, const std::atomic<bool>& stop,
                        SessionLimits& limits, SessionMetrics* metrics) {
  std::unique_ptr<lcm::LCM> images;  // frames get their own LCM instance, once a scene shows them
  // a scene's server; the first is built here, the next ones on the running server's builder
  // thread while it runs (Server::set_successor_builder), so a reload stops nothing until the
  // new pipeline is ready
  std::function<std::unique_ptr<Server>(Scene)> build = [&](Scene next) {
    // --case replaces the anatomy of every scene, the first and each one loaded over LCM (a
    // soft-tissue scene's procedural organ too: it runs on the case's organ)
    if (!options.case_dir.empty()) use_case_folder(next, options.case_dir);
    if ((next.xray || next.ultrasound) && !images) {
      auto opened = std::make_unique<lcm::LCM>(options.image_url);
      if (!opened->good()) throw std::runtime_error("cannot open the image LCM at " + options.image_url);
      images = std::move(opened);
    }
    auto server = std::make_unique<Server>(next, control, images.get(), &limits, metrics);
    server->cpu_latency_us = options.cpu_latency_us;
    server->on_debrief_request = options.write_debrief;
    server->set_successor_builder(build);
    return server;
  };
  // building the first scene is a start no loop watches: a signal during it ends the program at
  // once (realtime/stop_signal.h; nothing happens where no handler is installed, as in tests)
  realtime::mark_starting();
  std::unique_ptr<Server> server = build(std::move(scene));
  double ran_s = 0;  // running time so far (the first build does not count)
  // the pipeline a reload replaced, freed on a thread of its own while the next one starts (its
  // world, contact field and x-ray caches take tens of ms to give back)
  std::jthread reaper;
  for (;;) {
    const double left_s = options.duration_s > 0 ? std::max(options.duration_s - ran_s, 1e-3) : 0.0;
    realtime::mark_running(options.stop_within_s);
    StatsReport stats = server->run(left_s, stop);
    // the watchdog leaves the stats to be written; but a stop while the next scene builds waits
    // for that build (it cannot be cut short) when the server goes: the watchdog stays armed, and
    // ends the process within stop_within_s as a signal during a build always did
    if (!server->building_successor()) realtime::mark_stopped();
    if (reaper.joinable()) reaper.join();
    ran_s += stats.elapsed_s;
    std::unique_ptr<Server> next = server->take_successor();
    if (!next || stop) return stats;
    try {
      reaper = std::jthread([old = std::move(server)]() mutable { old.reset(); });
    } catch (const std::system_error&) {
      server.reset();  // no thread to spare: freed here
    }
    server = std::move(next);
  }
}

}  // namespace pcisim::server
