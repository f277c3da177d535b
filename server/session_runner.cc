#include "server/session_runner.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <optional>
#include <stdexcept>

#include "realtime/stop_signal.h"
#include "server/case_builder.h"
#include "server/server.h"

namespace pcisim::server {

StatsReport run_session(Scene scene, lcm::LCM& control, const SessionOptions& options, const std::atomic<bool>& stop,
                        SessionLimits& limits) {
  std::unique_ptr<lcm::LCM> images;  // frames get their own LCM instance, once a scene shows them
  std::optional<Scene> fallback;     // the last scene that was built
  double ran_s = 0;                  // running time so far (scene builds do not count)
  bool rebuilding_fallback = false;
  for (;;) {
    // building a scene is a start no loop watches: a signal during it ends the program at once
    // (realtime/stop_signal.h; nothing happens where no handler is installed, as in tests)
    realtime::mark_starting();
    // --case replaces the anatomy of every scene, the first and each one loaded over LCM (a
    // soft-tissue scene's procedural organ too: it runs on the case's organ)
    if (!options.case_dir.empty()) use_case_folder(scene, options.case_dir);
    if ((scene.xray || scene.ultrasound) && !images) {
      images = std::make_unique<lcm::LCM>(options.image_url);
      if (!images->good()) throw std::runtime_error("cannot open the image LCM at " + options.image_url);
    }
    std::unique_ptr<Server> server;
    try {
      server = std::make_unique<Server>(scene, control, images.get(), &limits);
    } catch (const std::exception& e) {
      // nothing to fall back to, or the fallback itself no longer builds (its files changed):
      // trying it again would loop for ever
      if (!fallback || rebuilding_fallback) throw;
      limits.count_scene_rejected();
      spdlog::error("session: refused scene {}: it cannot be built: {}; back to {}", scene.source, e.what(),
                    fallback->source);
      scene = *fallback;
      rebuilding_fallback = true;
      continue;
    }
    rebuilding_fallback = false;
    fallback = scene;
    server->cpu_latency_us = options.cpu_latency_us;
    const double left_s = options.duration_s > 0 ? std::max(options.duration_s - ran_s, 1e-3) : 0.0;
    realtime::mark_running(options.stop_within_s);
    StatsReport stats = server->run(left_s, stop);
    realtime::mark_stopped();  // the watchdog leaves the stats to be written
    ran_s += stats.elapsed_s;
    if (auto next = server->take_requested_scene(); next && !stop) {
      scene = std::move(*next);
      continue;
    }
    return stats;
  }
}

}  // namespace pcisim::server
