#pragma once
// A training session: one scene after another on the same LCM buses. A scene asked for over LCM
// is built while the running pipeline goes on (physics, force and frames do not stop for the
// build), then takes over; one that parses but cannot be built is refused (counted in the status)
// and the running scene simply goes on. The session's command bounds (contrast used, refusals)
// and its options (--case) carry across every pipeline.
#include <atomic>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>

#include "server/scene/scene.h"
#include "server/debrief/session_metrics.h"
#include "server/session_limits.h"
#include "server/stats.h"

namespace pcisim::server {

struct SessionOptions {
  double duration_s = 0;   // running time of all pipelines together; 0: until stopped
  int cpu_latency_us = 0;  // PM QoS while running; < 0 leaves the CPUs alone
  std::string image_url;   // the frames' LCM URL, opened when a scene has x-ray
  std::string case_dir;    // --case: every scene of the session runs on this case folder ("": its own anatomy)
  // once a scene runs, how long its clean stop (loops joined, zero force sent, stats written) may
  // take after SIGINT/SIGTERM before the process is ended (the bound is 1 s); while the
  // first scene builds, a signal ends the process at once (realtime/stop_signal.h); one that comes
  // while a reloaded scene builds ends it within this bound (that build cannot be cut short)
  double stop_within_s = 0.9;
  // writes the debrief so far when a session command asks for it (CMD_DEBRIEF); empty: none
  std::function<void()> write_debrief;
};

// throws when the first scene cannot be built (there is nothing to fall back to); returns the
// figures of the last pipeline
// `metrics` (optional) gathers the session's debrief figures across every pipeline
StatsReport run_session(Scene scene, lcm::LCM& control, const SessionOptions& options, const std::atomic<bool>& stop,
                        SessionLimits& limits, SessionMetrics* metrics = nullptr);

}  // namespace pcisim::server
