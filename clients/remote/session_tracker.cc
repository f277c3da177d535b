#include "clients/remote/session_tracker.h"

#include <algorithm>
#include <cmath>

#include "protocol/message_checks.h"

namespace pcisim::remote {

using I = pcisim_lcm::instrument_state_t;
using C = pcisim_lcm::session_command_t;

void SessionTracker::update_beam(int64_t now_ns) {
  const bool on = console_fluoro_ || console_cine_ || instrument_fluoro_ || instrument_cine_;
  if (on && !beam_on_) beam_since_ns_ = now_ns;
  if (!on && beam_on_) beam_total_ns_ += now_ns - beam_since_ns_;
  beam_on_ = on;
}

void SessionTracker::add_injection(double volume_ml) {
  if (injections_ >= options_.max_injections) return;
  ++injections_;
  injected_ml_ += volume_ml;
}

void SessionTracker::on_wire(const pcisim_lcm::wire_state_t& m, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  wire_ = m;
  wire_ns_ = now_ns;
}

void SessionTracker::on_status(const pcisim_lcm::sim_status_t& m, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  status_ = m;
  status_ns_ = now_ns;
  beam_s_at_status_ = local_beam_s(now_ns);
  injections_at_status_ = injections_;
  injected_ml_at_status_ = injected_ml_;
}

double SessionTracker::local_beam_s(int64_t now_ns) const {
  return (beam_total_ns_ + (beam_on_ ? now_ns - beam_since_ns_ : 0)) * 1e-9;
}

void SessionTracker::on_session(const pcisim_lcm::session_command_t& m, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  switch (m.command) {
    case C::CMD_FLUORO_PEDAL:
      console_fluoro_ = m.pedal_down != 0;
      break;
    case C::CMD_CINE:
      console_cine_ = m.pedal_down != 0;
      break;
    case C::CMD_CARM:
      // the server's own range check: what it ignores, we do not show
      if (std::abs(m.primary_angle_deg) <= 180 && std::abs(m.secondary_angle_deg) <= 90) {
        primary_deg_ = m.primary_angle_deg;
        secondary_deg_ = m.secondary_angle_deg;
      }
      break;
    case C::CMD_CONTRAST:
      // the server's rule: the volume the command names, else the scene's
      add_injection(protocol::is_commanded_contrast_volume(m.contrast_ml) ? m.contrast_ml : options_.injection_ml);
      break;
    default:
      break;
  }
  update_beam(now_ns);
}

void SessionTracker::on_instrument(const pcisim_lcm::instrument_state_t& m, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  if (m.device_id != options_.own_device_id) {
    other_instrument_ns_ = now_ns;
    other_device_id_ = m.device_id;
  }
  if (m.status == I::STATUS_FAULT) return;  // the server ignores a faulty device's buttons too
  instrument_fluoro_ = (m.buttons & I::BUTTON_FLUORO_PEDAL) != 0;
  instrument_cine_ = (m.buttons & I::BUTTON_CINE_PEDAL) != 0;
  const bool contrast = (m.buttons & I::BUTTON_CONTRAST) != 0;
  if (contrast && !contrast_button_) add_injection(options_.injection_ml);
  contrast_button_ = contrast;
  update_beam(now_ns);
}

void SessionTracker::on_frame(const pcisim_lcm::xray_frame_t& m, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  primary_deg_ = m.primary_angle_deg;  // the frame is the truth about the C-arm
  secondary_deg_ = m.secondary_angle_deg;
  frame_ns_ = now_ns;
  frame_sim_time_s_ = m.sim_time_s;
  frame_cine_ = m.cine != 0;
  frame_seq_ = m.seq;
  ++frames_;
}

double SessionTracker::fluoro_time_s(int64_t now_ns) const {
  std::lock_guard lock(mutex_);
  const double local = local_beam_s(now_ns);
  return status_ ? status_->fluoro_time_s + (local - beam_s_at_status_) : local;
}

int SessionTracker::injections() const {
  std::lock_guard lock(mutex_);
  return status_ ? status_->contrast_injections + (injections_ - injections_at_status_) : injections_;
}

bool SessionTracker::other_instrument_active(int64_t now_ns) const {
  std::lock_guard lock(mutex_);
  return other_instrument_ns_ > 0 && now_ns - other_instrument_ns_ < options_.instrument_active_ns;
}

std::optional<std::pair<double, double>> SessionTracker::wire_insertion_rotation() const {
  std::lock_guard lock(mutex_);
  if (!wire_) return std::nullopt;
  return std::make_pair(wire_->insertion_mm, wire_->rotation_rad);
}

int64_t SessionTracker::status_seq() const {
  std::lock_guard lock(mutex_);
  return status_ ? status_->seq : -1;
}

nlohmann::json SessionTracker::state_json(int64_t now_ns) const {
  const double fluoro_s = fluoro_time_s(now_ns);
  const int injections_now = injections();
  std::lock_guard lock(mutex_);
  nlohmann::json j = {{"type", "state"}};
  if (wire_) {
    const auto& w = *wire_;
    int contacts = 0;
    for (int8_t c : w.contact) contacts += c != 0;
    j["wire"] = {{"seq", w.seq},
                 {"sim_time_s", w.sim_time_s},
                 {"insertion_mm", w.insertion_mm},
                 {"rotation_rad", w.rotation_rad},
                 {"tip_mm", {w.tip_mm[0], w.tip_mm[1], w.tip_mm[2]}},
                 {"tip_branch", w.tip_branch},
                 {"heart_phase", w.heart_phase},
                 {"nodes", w.num_nodes},
                 {"contacts", contacts},
                 {"age_s", (now_ns - wire_ns_) * 1e-9}};
  } else {
    j["wire"] = nullptr;
  }
  j["fluoro"] = {{"on", beam_on_},
                 {"cine", console_cine_ || instrument_cine_},
                 {"pedal_console", console_fluoro_},
                 {"cine_console", console_cine_},
                 {"pedal_instrument", instrument_fluoro_ || instrument_cine_},
                 {"time_s", fluoro_s},
                 {"frames", frames_},
                 {"last_frame_seq", frame_seq_},
                 {"last_frame_age_s", frame_ns_ ? (now_ns - frame_ns_) * 1e-9 : -1.0}};
  j["carm"] = {{"primary_deg", primary_deg_ ? nlohmann::json(*primary_deg_) : nlohmann::json()},
               {"secondary_deg", secondary_deg_ ? nlohmann::json(*secondary_deg_) : nlohmann::json()}};
  // the server's volume where it reported one; the option's for what the bus added since
  const double used_ml = status_ ? status_->contrast_ml + (injected_ml_ - injected_ml_at_status_) : injected_ml_;
  j["contrast"] = {{"injections", injections_now}, {"used_ml", used_ml}};
  const bool other = other_instrument_ns_ > 0 && now_ns - other_instrument_ns_ < options_.instrument_active_ns;
  j["other_instrument"] = other ? nlohmann::json{{"device_id", other_device_id_}} : nlohmann::json();
  j["server_alive"] = status_ns_ > 0 && now_ns - status_ns_ < options_.server_alive_ns;
  j["paused"] = status_ ? status_->paused != 0 : false;
  return j;
}

void SessionTracker::on_metrics(const pcisim_lcm::session_metrics_t& m, int64_t) {
  std::lock_guard lock(mutex_);
  metrics_ = m;
}

nlohmann::json SessionTracker::debrief_json() const {
  std::lock_guard lock(mutex_);
  if (!metrics_) return nullptr;
  const auto& m = *metrics_;
  const nlohmann::json unknown = nullptr;
  return {{"seq", m.seq},
          {"procedure_time_s", m.procedure_time_s},
          {"fluoro_time_s", m.fluoro_time_s},
          {"cine_runs", m.cine_runs},
          {"contrast_ml", m.contrast_ml},
          {"contrast_injections", m.contrast_injections},
          {"air_kerma_mgy", m.air_kerma_mgy},
          {"dap_gycm2", m.dap_gycm2},
          {"tip_path_mm", m.tip_path_mm},
          {"tip_path_in_vessels_mm", m.tip_path_in_vessels_mm},
          {"target_branch", m.target_branch},
          {"wrong_branch_s", m.has_target ? nlohmann::json(m.wrong_branch_s) : unknown},
          {"target_reached_s", m.has_target && m.target_reached_s >= 0 ? nlohmann::json(m.target_reached_s) : unknown},
          {"peak_tip_force_n", m.tip_forces_known ? nlohmann::json(m.peak_tip_force_n) : unknown},
          {"force_events", m.tip_forces_known ? nlohmann::json(m.force_events) : unknown},
          {"prolapse_events", m.prolapse_events},
          {"buckling_events", m.buckling_events}};
}

nlohmann::json SessionTracker::status_json(int64_t now_ns) const {
  nlohmann::json debrief = debrief_json();
  std::lock_guard lock(mutex_);
  if (!status_) return nullptr;
  const auto& s = *status_;
  nlohmann::json effects = nlohmann::json::array();
  for (int i = 0; i < s.num_effects; ++i)
    effects.push_back({{"name", s.effect_name[i]}, {"step_ms_p50", s.effect_step_ms_p50[i]}});
  return {{"type", "status"},
          {"seq", s.seq},
          {"age_s", (now_ns - status_ns_) * 1e-9},
          {"haptic",
           {{"rate_hz", s.haptic_rate_hz},
            {"period_us_p50", s.haptic_period_us_p50},
            {"period_us_p99", s.haptic_period_us_p99},
            {"period_us_p999", s.haptic_period_us_p999},
            {"period_us_max", s.haptic_period_us_max},
            // jitter: how far the 99th percentile period strays from the typical one
            {"jitter_us_p99", s.haptic_period_us_p99 - s.haptic_period_us_p50},
            {"compute_us_p99", s.haptic_compute_us_p99},
            {"overruns", s.haptic_overruns}}},
          {"physics",
           {{"rate_hz", s.physics_rate_hz},
            {"step_ms_p50", s.physics_step_ms_p50},
            {"step_ms_p99", s.physics_step_ms_p99},
            {"overruns", s.physics_overruns}}},
          {"xray", {{"frames", s.xray_frames}, {"fps", s.xray_fps}}},
          {"lcm", {{"rx", s.lcm_rx}, {"tx", s.lcm_tx}, {"dropped_bad", s.lcm_dropped_bad}}},
          {"effects", effects},
          {"debrief", std::move(debrief)},
          {"paused", s.paused != 0}};
}

}  // namespace pcisim::remote
