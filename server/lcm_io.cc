#include "server/lcm_io.h"

#include <cmath>
#include <spdlog/spdlog.h>

#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/clock.h"
#include "realtime/realtime_setup.h"
#include "json/json_reader.h"

namespace pcisim::server {

LcmIo::LcmIo(lcm::LCM& lcm, SharedState& state, SessionLimits& limits, double scene_injection_ml, StatusSource status,
             BranchNamer branch_name, Instrument instrument, SessionMetrics* metrics)
    : lcm_(lcm),
      state_(state),
      limits_(limits),
      scene_injection_ml_(scene_injection_ml),
      status_(std::move(status)),
      branch_name_(std::move(branch_name)),
      metrics_(metrics) {
  subscriptions_ = {instrument == Instrument::kProbe
                        ? lcm_.subscribe(protocol::kProbeChannel, &LcmIo::on_probe, this)
                        : lcm_.subscribe(protocol::kInstrumentChannel, &LcmIo::on_instrument, this),
                    lcm_.subscribe(protocol::kSessionChannel, &LcmIo::on_session, this)};
}

// the lcm::LCM outlives this object (a scene reload builds a new server on it): our handlers go
// with us, or the next server's messages reach a dead `this` as well
LcmIo::~LcmIo() {
  stop();
  for (lcm::Subscription* s : subscriptions_) lcm_.unsubscribe(s);
}

void LcmIo::start() {
  running_ = receiving_ = true;
  // below the haptic loop (80), above everything else: a CPU hog must not delay force commands
  rx_ = std::thread([this] {
    realtime::try_sched_fifo(70);
    rx_loop();
  });
  tx_ = std::thread([this] {
    realtime::try_sched_fifo(70);
    tx_loop();
  });
}

void LcmIo::stop_receiving() {
  receiving_ = false;
  if (rx_.joinable()) rx_.join();
}

void LcmIo::stop() {
  if (!running_.exchange(false)) return;
  stop_receiving();
  if (tx_.joinable()) tx_.join();
  publish_zero_force();
}

void LcmIo::publish_zero_force() {
  pcisim_lcm::force_command_t zero{};
  zero.utime = realtime::monotonic_us();
  zero.seq = -1;  // not a haptic tick: the server's last word
  zero.instrument_seq = last_instrument_seq_;
  zero.flags = pcisim_lcm::force_command_t::FLAG_FADED;
  zero_publisher_.publish(lcm_, force_channel_, zero);
  state_.lcm_tx.fetch_add(1, std::memory_order_relaxed);
}

void LcmIo::on_instrument(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  state_.lcm_rx.fetch_add(1, std::memory_order_relaxed);
  if (!protocol::decode_checked(*rbuf, instrument_msg_)) {
    state_.lcm_dropped_bad.fetch_add(1, std::memory_order_relaxed);
    state_.instrument_rejected.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  // a device in fault sends no motion: leave the last sample to go stale and fade; its pedals
  // cannot be trusted either, so the beam goes off
  if (instrument_msg_.status == pcisim_lcm::instrument_state_t::STATUS_FAULT) {
    state_.fluoro_pedal_instrument.store(false, std::memory_order_relaxed);
    state_.cine_instrument.store(false, std::memory_order_relaxed);
    return;
  }
  const auto& m = instrument_msg_;
  using I = pcisim_lcm::instrument_state_t;
  state_.fluoro_pedal_instrument.store((m.buttons & I::BUTTON_FLUORO_PEDAL) != 0, std::memory_order_relaxed);
  state_.cine_instrument.store((m.buttons & I::BUTTON_CINE_PEDAL) != 0, std::memory_order_relaxed);
  state_.instrument_heard_ns.store(realtime::monotonic_ns(), std::memory_order_relaxed);
  const bool contrast = (m.buttons & I::BUTTON_CONTRAST) != 0;
  if (contrast && !state_.contrast_button_down) add_injection();
  state_.contrast_button_down = contrast;
  InstrumentSlot slot;
  slot.seq = m.seq;
  slot.buttons = m.buttons;
  slot.sample.received_us = realtime::monotonic_us();
  slot.sample.insertion_m = m.insertion_mm * 1e-3;
  slot.sample.rotation_rad = m.rotation_rad;
  slot.sample.insertion_rate_m_per_s = m.insertion_rate_mm_s * 1e-3;
  slot.sample.rotation_rate_rad_per_s = m.rotation_rate_rad_s;
  last_instrument_seq_ = m.seq;
  state_.instrument_for_haptics.write_slot() = slot;
  state_.instrument_for_haptics.publish();
  state_.instrument_for_physics.write_slot() = slot;
  state_.instrument_for_physics.publish();
}

// the probe: its pose for physics, and for the haptic loop the face's depth along its own beam
// (the one axis the force is rendered on) with its rate from the previous sample
void LcmIo::on_probe(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  state_.lcm_rx.fetch_add(1, std::memory_order_relaxed);
  if (!protocol::decode_checked(*rbuf, probe_msg_)) {
    state_.lcm_dropped_bad.fetch_add(1, std::memory_order_relaxed);
    state_.instrument_rejected.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  const auto& m = probe_msg_;
  if (m.status == pcisim_lcm::probe_state_t::STATUS_FAULT) return;  // goes stale; the force fades
  state_.instrument_heard_ns.store(realtime::monotonic_ns(), std::memory_order_relaxed);
  InstrumentSlot slot;
  slot.seq = m.seq;
  slot.buttons = m.buttons;
  slot.probe_present = true;
  const auto& q = m.orientation_wxyz;
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);  // within 1 % of 1 (checked)
  for (int k = 0; k < 4; ++k) slot.probe_orientation_wxyz[k] = q[k] / n;
  for (int k = 0; k < 3; ++k) slot.probe_position_m[k] = m.position_mm[k] * 1e-3;
  slot.probe_depth_mm = m.depth_mm;
  slot.probe_gain_db = m.gain_db;
  // the depth along the beam the last physics step linearised at (its model's x0 is measured along
  // the same beam): a probe turned in place keeps its depth
  const double beam[3] = {state_.probe_beam_x.load(std::memory_order_relaxed),
                          state_.probe_beam_y.load(std::memory_order_relaxed),
                          state_.probe_beam_z.load(std::memory_order_relaxed)};
  const double depth_m =
      beam[0] * slot.probe_position_m[0] + beam[1] * slot.probe_position_m[1] + beam[2] * slot.probe_position_m[2];
  slot.sample.received_us = realtime::monotonic_us();
  slot.sample.insertion_m = depth_m;
  // the rate over the sender's clock (arrival times bunch when the rx thread drains a backlog);
  // samples closer than 0.2 ms keep the last rate, a gap over 0.1 s is a jump, not a velocity
  const int64_t dt_us = m.utime - last_probe_us_;
  if (last_probe_us_ == 0 || dt_us <= 0 || dt_us > 100'000) {
    probe_rate_m_per_s_ = 0.0;
  } else if (dt_us >= 200) {
    probe_rate_m_per_s_ = (depth_m - last_probe_depth_m_) / (dt_us * 1e-6);
  }
  slot.sample.insertion_rate_m_per_s = probe_rate_m_per_s_;
  if (last_probe_us_ == 0 || dt_us <= 0 || dt_us >= 200) {
    last_probe_us_ = m.utime;
    last_probe_depth_m_ = depth_m;
  }
  last_instrument_seq_ = m.seq;
  state_.instrument_for_haptics.write_slot() = slot;
  state_.instrument_for_haptics.publish();
  state_.instrument_for_physics.write_slot() = slot;
  state_.instrument_for_physics.publish();
}

void LcmIo::on_session(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  state_.lcm_rx.fetch_add(1, std::memory_order_relaxed);
  if (!protocol::decode_checked(*rbuf, session_msg_)) {
    state_.lcm_dropped_bad.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  using C = pcisim_lcm::session_command_t;
  switch (session_msg_.command) {
    // logged on a change only: a stream of the same command must not flood the log
    case C::CMD_PAUSE:
      if (!state_.paused.exchange(true)) spdlog::info("session: paused");
      break;
    case C::CMD_RESUME:
      if (state_.paused.exchange(false)) spdlog::info("session: resumed");
      break;
    case C::CMD_RESET:
      if (!limits_.allow_reset(realtime::monotonic_ns())) {
        refuse("reset", fmt::format("within {} s of the last one", limits_.params().min_reset_interval_s));
        break;
      }
      state_.reset_requested = true;
      spdlog::info("session: reset");
      break;
    case C::CMD_LOAD_SCENE:
      if (!limits_.allow_scene_load(realtime::monotonic_ns())) {
        refuse("scene load", fmt::format("within {} s of the last one", limits_.params().min_scene_load_interval_s));
        break;
      }
      request_scene(session_msg_.scene_path);
      break;
    case C::CMD_FLUORO_PEDAL:
      state_.fluoro_pedal_console = session_msg_.pedal_down != 0;
      break;
    case C::CMD_CINE:
      state_.cine_console = session_msg_.pedal_down != 0;
      break;
    case C::CMD_CARM:
      if (std::abs(session_msg_.primary_angle_deg) > 180 || std::abs(session_msg_.secondary_angle_deg) > 90) {
        refuse("C-arm move", fmt::format("angles ({}, {}) out of range", session_msg_.primary_angle_deg,
                                         session_msg_.secondary_angle_deg));
        break;
      }
      // the newest target; the x-ray thread moves there when the last move's interval is over
      state_.carm_target_seq.fetch_add(1, std::memory_order_acq_rel);  // odd: writing
      state_.carm_target_primary_deg = session_msg_.primary_angle_deg;
      state_.carm_target_secondary_deg = session_msg_.secondary_angle_deg;
      state_.carm_target_seq.fetch_add(1, std::memory_order_acq_rel);  // even: whole
      state_.carm_requests.fetch_add(1, std::memory_order_relaxed);
      break;
    case C::CMD_CONTRAST:
      add_injection(session_msg_.contrast_ml, session_msg_.contrast_ml_s);
      break;
    case C::CMD_DEBRIEF:
      // written off this thread (a page takes tens of ms: the instrument's samples must not wait)
      state_.debrief_requested = true;
      break;
    default:
      refuse("command", fmt::format("unknown command {}", static_cast<int>(session_msg_.command)));
  }
}

void LcmIo::refuse(const char* what, const std::string& why) {
  const int64_t now = realtime::monotonic_ns();
  if (now - last_refusal_log_ns_ < 1'000'000'000) {
    ++refusals_unlogged_;
    return;
  }
  if (refusals_unlogged_ > 0)
    spdlog::warn("session: {} refused: {} ({} more refusals in the last second, not logged)", what, why,
                 refusals_unlogged_);
  else
    spdlog::warn("session: {} refused: {}", what, why);
  last_refusal_log_ns_ = now;
  refusals_unlogged_ = 0;
}

// single writer (this thread): the entry is written before the count that publishes it
void LcmIo::add_injection(double volume_ml, double rate_ml_per_s) {
  const int n = state_.injections.load(std::memory_order_relaxed);
  // a volume the command may name, over 0.2-10 s; anything else falls back to the scene's
  const bool volume_ok = protocol::is_commanded_contrast_volume(volume_ml);
  const double injected_ml = volume_ok ? volume_ml : scene_injection_ml_;
  if (n >= SharedState::kMaxInjections) {
    limits_.count_injection_refused();
    refuse("contrast", fmt::format("this pipeline's {} injections are used up", SharedState::kMaxInjections));
    return;
  }
  if (!limits_.allow_injection(realtime::monotonic_ns(), injected_ml)) {
    refuse("contrast", fmt::format("{} ml over the limits ({} per minute, {} ml per session; {:.1f} ml used)",
                                   injected_ml, limits_.params().max_injections_per_min,
                                   limits_.params().max_contrast_ml, limits_.contrast_ml()));
    return;
  }
  state_.injection_start_s[n] = state_.sim_time_s.load(std::memory_order_relaxed);
  state_.injection_volume_ml[n] = volume_ok ? volume_ml : 0.0;
  const double duration_s =
      volume_ok && std::isfinite(rate_ml_per_s) && rate_ml_per_s > 0 ? volume_ml / rate_ml_per_s : 0.0;
  state_.injection_duration_s[n] = duration_s >= 0.2 && duration_s <= 10.0 ? duration_s : 0.0;
  state_.injections.store(n + 1, std::memory_order_release);
  if (metrics_) metrics_->record_injection(injected_ml, realtime::monotonic_ns());
}

// parsing happens here, off the loops; a bad scene is refused and the running one stays
void LcmIo::request_scene(const std::string& path) {
  try {
    Scene scene = load_scene_file(path);
    std::lock_guard lock(state_.scene_mutex);
    state_.requested_scene = std::move(scene);
    state_.scene_requested = true;
    limits_.book_scene_load(realtime::monotonic_ns());
    spdlog::info("session: scene {} accepted, building its pipeline", path);
  } catch (const std::exception& e) {  // json::JsonError, or anything else a path can provoke
    limits_.count_scene_rejected();
    refuse("scene", e.what());
  }
}

void LcmIo::rx_loop() {
  while (receiving_.load(std::memory_order_relaxed)) lcm_.handleTimeout(20);
}

void LcmIo::publish_wire(const physics::WorldSnapshot& s) {
  auto& m = wire_msg_;
  m.utime = realtime::monotonic_us();
  m.seq = s.step;
  m.sim_time_s = s.time_s;
  m.insertion_mm = s.insertion_m * 1e3;
  m.rotation_rad = s.rotation_rad;
  m.num_nodes = static_cast<int32_t>(s.wire_nodes_m.size());
  if (m.node_mm.size() != s.wire_nodes_m.size()) m.node_mm.assign(s.wire_nodes_m.size(), std::vector<float>(3));
  m.contact.resize(s.wire_nodes_m.size());
  if (m.contact_force_n.size() != s.wire_nodes_m.size())
    m.contact_force_n.assign(s.wire_nodes_m.size(), std::vector<float>(3));
  for (size_t i = 0; i < s.wire_nodes_m.size(); ++i) {
    for (int k = 0; k < 3; ++k) m.node_mm[i][k] = static_cast<float>(s.wire_nodes_m[i][k] * 1e3);
    m.contact[i] = i < s.wire_contact.size() ? static_cast<int8_t>(s.wire_contact[i]) : 0;
    for (int k = 0; k < 3; ++k)
      m.contact_force_n[i][k] =
          i < s.wire_contact_force_n.size() ? static_cast<float>(s.wire_contact_force_n[i][k]) : 0.0f;
  }
  m.tip_force_n = s.tip_force_n;
  m.hub_force_n = s.hub_force_n;
  m.hub_torque_nm = s.hub_torque_nm;
  for (int k = 0; k < 3; ++k) m.tip_mm[k] = s.tip_m[k] * 1e3;
  if (branch_name_)
    m.tip_branch = branch_name_(s.tip_branch);  // into the string's own buffer once it is long enough
  else
    m.tip_branch.clear();
  m.heart_phase = s.heart_phase;
  tx_publisher_.publish(lcm_, wire_channel_, m);
  state_.lcm_tx.fetch_add(1, std::memory_order_relaxed);
  // the debrief's figures from exactly the states the bus carried
  if (metrics_)
    metrics_->record_wire(s, state_.carm_primary_deg.load(std::memory_order_relaxed),
                          state_.carm_secondary_deg.load(std::memory_order_relaxed), realtime::monotonic_ns());
}

void LcmIo::publish_forces() {
  ForceSlot slot;
  while (state_.forces.pop(slot)) {
    force_msg_.utime = slot.utime;
    force_msg_.seq = slot.tick;
    force_msg_.instrument_seq = slot.instrument_seq;
    force_msg_.axial_force_n = slot.force.axial_force_n;
    force_msg_.torque_nmm = slot.force.torque_nm * 1e3;
    force_msg_.axial_stiffness_n_per_mm = slot.force.axial_stiffness_n_per_m * 1e-3;
    force_msg_.torsional_stiffness_nmm_per_rad = slot.force.torsional_stiffness_nm_per_rad * 1e3;
    force_msg_.flags = slot.force.flags;
    tx_publisher_.publish(lcm_, force_channel_, force_msg_);
    state_.lcm_tx.fetch_add(1, std::memory_order_relaxed);
  }
}

void LcmIo::publish_status() {
  if (metrics_) publish_metrics();
  if (!status_) return;
  status_(status_msg_);
  status_msg_.seq = status_seq_++;
  tx_publisher_.publish(lcm_, status_channel_, status_msg_);
  state_.lcm_tx.fetch_add(1, std::memory_order_relaxed);
}

// the debrief so far, its figures without their lists (nothing allocated once the branch's name fits)
void LcmIo::publish_metrics() {
  const int64_t now_ns = realtime::monotonic_ns();
  DebriefFigures& f = metrics_figures_;
  metrics_->figures_without_lists(now_ns, &f);
  auto& m = metrics_msg_;
  m.utime = now_ns / 1000;
  m.seq = metrics_seq_++;
  m.procedure_time_s = f.procedure_time_s;
  m.fluoro_time_s = f.fluoro_time_s;
  m.cine_time_s = f.cine_time_s;
  m.cine_runs = f.cine_runs;
  m.fluoro_pulses = f.fluoro_pulses;
  m.cine_frames = f.cine_frames;
  m.contrast_injections = f.contrast_injections;
  m.contrast_ml = f.contrast_ml;
  m.air_kerma_mgy = f.air_kerma_mgy;
  m.dap_gycm2 = f.dap_gycm2;
  m.tip_path_mm = f.tip_path_mm;
  m.tip_path_projected_mm = f.tip_path_projected_mm;
  m.tip_path_in_vessels_mm = f.tip_path_in_vessels_mm;
  m.has_target = f.has_target ? 1 : 0;
  m.target_branch.assign(f.target_branch);
  m.wrong_branch_s = f.wrong_branch_s;
  m.target_reached_s = f.target_reached_s;
  m.tip_forces_known = f.tip_forces_known ? 1 : 0;
  m.peak_tip_force_n = f.peak_tip_force_n;
  m.tip_force_above_threshold_s = f.tip_force_above_threshold_s;
  m.force_events = f.force_events;
  m.prolapse_events = f.prolapse_events;
  m.buckling_events = f.buckling_events;
  m.wire_restarts = f.resets;
  tx_publisher_.publish(lcm_, metrics_channel_, m);
  state_.lcm_tx.fetch_add(1, std::memory_order_relaxed);
}

void LcmIo::tx_loop() {
  int64_t next_status_us = realtime::monotonic_us() + 1'000'000;
  while (running_.load(std::memory_order_relaxed)) {
    // force commands first: they are the latency-critical stream
    publish_forces();
    if (state_.snapshot_for_tx.refresh()) publish_wire(state_.snapshot_for_tx.read_slot());
    const int64_t now_us = realtime::monotonic_us();
    if (now_us >= next_status_us) {
      publish_status();
      next_status_us += 1'000'000;
    }
    realtime::sleep_until_ns(realtime::monotonic_ns() + 200'000);
  }
}

}  // namespace pcisim::server
