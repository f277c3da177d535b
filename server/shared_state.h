#pragma once
// Everything the server's threads hand each other. Each channel has one writer and one reader:
// triple buffers for "newest wins" state, an SPSC ring for the force command stream, relaxed
// atomics for counters. Nothing here locks.
#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <optional>

#include "haptics/force_evaluator.h"
#include "physics/local_force_model.h"
#include "physics/world_snapshot.h"
#include "realtime/latency_histogram.h"
#include "realtime/spsc_ring.h"
#include "realtime/triple_buffer.h"
#include "server/scene/scene.h"

namespace pcisim::server {

struct InstrumentSlot {
  haptics::InstrumentSample sample;  // SI, stamped with the monotonic receive time
  int64_t seq = -1;
  int32_t buttons = 0;
  // the ultrasound probe (PCISIM_PROBE): its pose for physics; sample.insertion_m is then the
  // face's depth along the beam (m) and the haptic loop renders the force along it
  bool probe_present = false;
  std::array<double, 3> probe_position_m{};
  std::array<double, 4> probe_orientation_wxyz{1.0, 0.0, 0.0, 0.0};
  double probe_depth_mm = 0.0, probe_gain_db = 0.0;
};

struct ForceSlot {
  int64_t utime = 0;
  int64_t tick = 0;
  int64_t instrument_seq = -1;
  haptics::ForceOutput force;
};

struct LoopStats {
  realtime::LatencyHistogram period_ns;   // wake-to-wake
  realtime::LatencyHistogram compute_ns;  // work per iteration
  realtime::LatencyHistogram late_ns;     // wake time minus deadline
  std::atomic<int64_t> iterations{0};
  std::atomic<int64_t> overruns{0};
  std::atomic<int64_t> first_wake_ns{0}, last_wake_ns{0};

  // the rate the loop achieved while it ran (a stopped loop does not dilute it)
  double rate_hz() const {
    const int64_t span = last_wake_ns.load() - first_wake_ns.load();
    return span > 0 ? static_cast<double>(iterations.load() - 1) * 1e9 / static_cast<double>(span) : 0.0;
  }
  void mark_wake(int64_t wake_ns) {
    if (first_wake_ns.load(std::memory_order_relaxed) == 0) first_wake_ns.store(wake_ns, std::memory_order_relaxed);
    last_wake_ns.store(wake_ns, std::memory_order_relaxed);
  }
};

struct SharedState {
  // lcm rx -> haptic, lcm rx -> physics (a triple buffer has one reader, so one each)
  realtime::TripleBuffer<InstrumentSlot> instrument_for_haptics;
  realtime::TripleBuffer<InstrumentSlot> instrument_for_physics;
  // physics -> haptic, physics -> lcm tx
  realtime::TripleBuffer<physics::LocalForceModel> force_model;
  realtime::TripleBuffer<physics::WorldSnapshot> snapshot_for_tx;
  realtime::TripleBuffer<physics::WorldSnapshot> snapshot_for_xray;  // published only when the scene has xray
  std::atomic<bool> xray_enabled{false};
  realtime::TripleBuffer<physics::WorldSnapshot> snapshot_for_ultrasound;  // only when the scene has ultrasound
  std::atomic<bool> ultrasound_enabled{false};
  realtime::LatencyHistogram ultrasound_render_ns;
  std::atomic<int64_t> ultrasound_frames{0};
  std::atomic<double> sim_time_s{0};
  // haptic -> lcm tx
  realtime::SpscRing<ForceSlot, 1024> forces;
  std::atomic<int64_t> forces_dropped{0};

  LoopStats haptic, physics;
  std::atomic<int64_t> lcm_rx{0}, lcm_tx{0}, lcm_dropped_bad{0};
  std::atomic<int64_t> instrument_rejected{0};  // non-finite or fault samples (also in dropped_bad)

  // session control from lcm rx, read by physics
  std::atomic<bool> paused{false};
  std::atomic<bool> reset_requested{false};
  std::atomic<bool> debrief_requested{false};  // CMD_DEBRIEF: the main thread writes it (Server::run)
  std::atomic<bool> stop{false};               // the physics, x-ray and ultrasound loops
  // the haptic loop's own stop, set after the loops that feed its model have stopped: its force
  // stays fresh while they wind down (a reload hands over to the next pipeline meanwhile)
  std::atomic<bool> stop_haptic{false};
  std::atomic<int64_t> inject_stall_us{0};  // fault injection: the next physics step takes this long

  // a validated scene asked for over LCM; its pipeline is built while this one runs, then takes over
  std::mutex scene_mutex;
  std::optional<Scene> requested_scene;
  std::atomic<bool> scene_requested{false};

  // fluoroscopy controls: written by lcm rx, read by the x-ray thread. The instrument's pedals
  // count only while its samples arrive: a crashed bridge or unplugged box lifts them
  static constexpr int64_t kInstrumentPedalTimeoutNs = 250'000'000;
  std::atomic<bool> fluoro_pedal_instrument{false}, cine_instrument{false};
  std::atomic<int64_t> instrument_heard_ns{0};  // monotonic time of the last good instrument sample
  bool instrument_pedal_down(const std::atomic<bool>& pedal, int64_t now_ns) const {
    return pedal.load(std::memory_order_relaxed) &&
           now_ns - instrument_heard_ns.load(std::memory_order_relaxed) <= kInstrumentPedalTimeoutNs;
  }
  std::atomic<bool> fluoro_pedal_console{false}, cine_console{false};
  // the C-arm: lcm rx writes the newest target (a sequence count, odd while it writes, lets the
  // x-ray thread see the two angles whole); the x-ray thread applies it at most once per
  // min_carm_move_interval_s, newest target winning, and publishes the pose it applied
  std::atomic<int64_t> carm_target_seq{0};
  std::atomic<double> carm_target_primary_deg{0}, carm_target_secondary_deg{0};
  std::atomic<double> carm_primary_deg{0}, carm_secondary_deg{0};  // applied
  std::atomic<int64_t> carm_requests{0}, carm_moves{0};
  static constexpr int kMaxInjections = 256;
  std::array<double, kMaxInjections> injection_start_s{};  // sim time of each contrast injection
  // each injection's volume and duration; 0: the scene's contrast.injection_ml / injection_s
  std::array<double, kMaxInjections> injection_volume_ml{}, injection_duration_s{};
  std::atomic<int> injections{0};     // entries written (single writer: lcm rx)
  bool contrast_button_down = false;  // lcm rx only: edge detection
  realtime::LatencyHistogram xray_render_ns;
  std::atomic<int64_t> xray_frames{0};  // every frame published, the C-arm moves' extra ones too
  std::atomic<int64_t> xray_pulses{0};  // the frames on the pulse schedule
  std::atomic<int64_t> xray_on_ns{0};   // beam time: pedal-down wall time, plus each press's first pulse period

  // a few figures of the newest step for the once-a-second log line
  std::atomic<double> wire_insertion_mm{0}, wire_rotation_rad{0};
  std::atomic<int> wire_tip_branch{-1}, wire_contacts{0};
  std::atomic<double> probe_force_n{0};  // the soft-tissue scene: the tissue's push along the probe's beam
  // the beam the last physics step linearised the probe's force along (physics writes, lcm rx
  // reads): the rx thread measures each sample's depth along it, so turning the probe in place is
  // not felt as pressing. A torn read mixes two unit vectors one step apart: harmless
  std::atomic<double> probe_beam_x{0}, probe_beam_y{0}, probe_beam_z{1};
};

}  // namespace pcisim::server
