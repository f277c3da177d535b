#pragma once
// The figures the server reports: at exit as JSON (--stats-json), once a second as sim_status_t.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pcisim_lcm/sim_status_t.hpp"
#include "server/physics_loop.h"
#include "server/shared_state.h"

namespace pcisim::server {

struct Percentiles {
  double p50 = 0, p99 = 0, p999 = 0, max = 0;
};

struct StatsReport {
  double elapsed_s = 0;
  double haptic_rate_hz = 0;
  Percentiles haptic_period_us, haptic_compute_us, haptic_late_us;
  int64_t haptic_ticks = 0, haptic_overruns = 0, forces_dropped = 0;
  bool haptic_fifo = false;
  bool cpu_latency_held = false;  // PM QoS request granted
  double physics_rate_hz = 0, physics_target_hz = 0;
  Percentiles physics_step_ms, physics_period_ms;
  int64_t physics_steps = 0, physics_overruns = 0;
  std::vector<std::pair<std::string, double>> effect_step_ms_p50;
  int64_t xray_frames = 0;
  double xray_fps = 0;  // frames per second while a pedal was down
  Percentiles xray_render_ms;
  int64_t ultrasound_frames = 0;  // the soft-tissue scene's B-mode frames
  Percentiles ultrasound_render_ms;
  std::vector<std::string> effects;  // every effect the scene built (physics and x-ray)
  int64_t lcm_rx = 0, lcm_tx = 0, lcm_dropped_bad = 0;
  // the session so far (across scene reloads): contrast and refused console commands
  int64_t contrast_injections = 0;
  double contrast_ml = 0;
  int64_t resets_refused = 0, scene_loads_refused = 0, scenes_rejected = 0, injections_refused = 0;
  int64_t carm_moves_coalesced = 0;
};

Percentiles percentiles(const realtime::LatencyHistogram& h, double scale);

// rates are those the loops achieved while running; elapsed_s is the whole run. Into `r` in
// place: its vectors and strings keep their storage, so the once-a-second status allocates
// nothing once warm (issue #36 item 5)
void collect_stats(const SharedState& state, const PhysicsLoop& physics, double elapsed_s, bool haptic_fifo,
                   StatsReport* r);
nlohmann::json to_json(const StatsReport& r);
// into `m` in place (its effect names keep their storage); seq and the session's cath-lab fields
// are the caller's
void to_message(const StatsReport& r, int64_t utime, int64_t seq, bool paused, pcisim_lcm::sim_status_t* m);
std::string human_summary(const StatsReport& r);

}  // namespace pcisim::server
