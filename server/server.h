#pragma once
// The server: owns the threads (haptic 1 kHz, physics at the scene rate, LCM I/O) and wires the
// scene's effects, haptics and protocol together.
#include <atomic>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <string>

#include "server/scene/scene.h"
#include "server/debrief/session_metrics.h"
#include "server/session_limits.h"
#include "server/stats.h"

namespace pcisim::server {

class Server {
 public:
  // builds the scene's world and, when the scene lists xray, the fluoroscopy renderer (may take
  // seconds) before any thread starts. Frames go out on `images` (their own LCM instance); with
  // no images instance they are rendered and counted but not sent.
  // `limits` carries the session's command bounds across scene reloads (owned by the caller, who
  // runs one server after another); without it the server keeps its own.
  // `metrics` likewise carries the session's debrief figures (server/debrief/session_metrics.h).
  Server(const Scene& scene, lcm::LCM& control, lcm::LCM* images = nullptr, SessionLimits* limits = nullptr,
         SessionMetrics* metrics = nullptr);
  ~Server();

  // runs until duration_s elapses (0 = no limit) or *stop becomes true; on the way out it stops
  // the loops and publishes a zero force command. Returns the final figures.
  StatsReport run(double duration_s, const std::atomic<bool>& stop);

  // CPU wake-up latency to ask for while running (PM QoS); < 0 leaves the CPUs alone
  int cpu_latency_us = 0;

  // fault injection for tests and benchmarks: the next physics step takes seconds longer
  void inject_physics_stall(double seconds);

  // a scene a session command asked for while running (run() returned early for it; without a
  // successor builder)
  std::optional<Scene> take_requested_scene();

  // with a successor builder, a scene asked for is built on a builder thread while this server
  // keeps running (issue #36: a reload stopped physics and the force for the whole build); run()
  // returns once it is built, and take_successor() hands it over. A scene that cannot be built is
  // refused (logged, counted in the session's limits) and this one runs on. A scene asked for
  // while another builds is kept for the one being built, which builds it next. A stop while a
  // scene builds waits for that build when the server is destroyed (run_session keeps the stop
  // watchdog armed meanwhile).
  using SuccessorBuilder = std::function<std::unique_ptr<Server>(Scene)>;
  void set_successor_builder(SuccessorBuilder build);
  std::unique_ptr<Server> take_successor();
  // a successor is being built (run() returned for a stop meanwhile: destroying this server waits
  // for that build)
  bool building_successor() const;

  // the status message run() publishes once a second (sim_status_t), filled in place: its rates
  // are over the time since the last call (public for the test that counts its allocations:
  // none once warm, issue #36 item 5)
  void fill_status(pcisim_lcm::sim_status_t* m);
  // a session command asked for the debrief so far (CMD_DEBRIEF): called on run()'s thread, between
  // its looks at the clock (without one, the request is logged and dropped)
  std::function<void()> on_debrief_request;
  // names of the vessel branches, for wire_state_t (index -> name, "" when unknown)
  std::function<const std::string&(int)> branch_namer;  // (LcmIo::BranchNamer)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pcisim::server
