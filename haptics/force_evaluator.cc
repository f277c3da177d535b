#include "haptics/force_evaluator.h"

#include <algorithm>
#include <cmath>

namespace pcisim::haptics {
namespace {

double clamp_abs(double v, double limit, int32_t& flags) {
  if (std::abs(v) <= limit) return v;
  flags |= kFlagClamped;
  return std::copysign(limit, v);
}

double slew(double target, double last, double max_step) {
  return last + std::clamp(target - last, -max_step, max_step);
}

bool finite(const physics::LocalForceModel& m) {
  for (double v : {m.x0_m, m.f0_n, m.k_n_per_m, m.b_n_s_per_m, m.q0_rad, m.t0_nm, m.kt_nm_per_rad, m.bt_nm_s_per_rad})
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace

ForceEvaluator::ForceEvaluator(const HapticParams& params)
    : params_((validate(params), params)),
      axial_pc_(params.passivity_max_damping_n_s_per_m),
      torque_pc_(params.passivity_max_damping_nm_s_per_rad) {}

void ForceEvaluator::set_model(const physics::LocalForceModel& model, int64_t now_us) {
  // a broken model is never blended or extrapolated from
  previous_model_ = model_;
  has_previous_ = has_model_ && finite(model_);
  model_ = model;
  has_model_ = model.valid_for_us > 0;
  model_arrived_us_ = now_us;
}

// f = f0 + K (x - x0) + B v, and the torque likewise: both terms resist (local_force_model.h)
ForceEvaluator::Raw ForceEvaluator::evaluate(const physics::LocalForceModel& m, const InstrumentSample& s) {
  return {m.f0_n + m.k_n_per_m * (s.insertion_m - m.x0_m) + m.b_n_s_per_m * s.insertion_rate_m_per_s,
          m.t0_nm + m.kt_nm_per_rad * (s.rotation_rad - m.q0_rad) + m.bt_nm_s_per_rad * s.rotation_rate_rad_per_s};
}

ForceEvaluator::Raw ForceEvaluator::interpolate(const InstrumentSample& s, int64_t now_us) const {
  if (!has_model_) return {0.0, 0.0};
  switch (params_.interpolation) {
    case Interpolation::kZeroOrderHold:
      return {model_.f0_n, model_.t0_nm};
    case Interpolation::kLinearExtrapolation: {
      const double span_s = (model_.made_utime - previous_model_.made_utime) * 1e-6;
      if (!has_previous_ || span_s <= 0) return {model_.f0_n, model_.t0_nm};
      const double u = (now_us - model_.made_utime) * 1e-6 / span_s;
      return {model_.f0_n + u * (model_.f0_n - previous_model_.f0_n),
              model_.t0_nm + u * (model_.t0_nm - previous_model_.t0_nm)};
    }
    case Interpolation::kLocalModel:
      break;
  }
  // blend from the previous model to the new one so a model change is never a force step
  Raw raw = evaluate(model_, s);
  const double blend_s = params_.blend_ms * 1e-3;
  const double w = blend_s > 0 ? std::clamp((now_us - model_arrived_us_) * 1e-6 / blend_s, 0.0, 1.0) : 1.0;
  if (has_previous_ && w < 1.0) {
    const Raw old = evaluate(previous_model_, s);
    raw.force_n = old.force_n + w * (raw.force_n - old.force_n);
    raw.torque_nm = old.torque_nm + w * (raw.torque_nm - old.torque_nm);
  }
  return raw;
}

bool ForceEvaluator::model_stale(int64_t now_us) const {
  return !has_model_ || now_us - model_.made_utime > model_.valid_for_us;
}

ForceOutput ForceEvaluator::tick(const InstrumentSample& sample, int64_t now_us) {
  ForceOutput out;
  const double dt_s = last_tick_us_ > 0 ? std::clamp((now_us - last_tick_us_) * 1e-6, 0.0, 0.1) : 1e-3;
  last_tick_us_ = now_us;
  const Raw raw = interpolate(sample, now_us);

  // nan guard: a non-finite anything means zero force this tick and a ramp-in afterwards
  if (!std::isfinite(raw.force_n) || !std::isfinite(raw.torque_nm) || !std::isfinite(sample.insertion_rate_m_per_s) ||
      !std::isfinite(sample.rotation_rate_rad_per_s)) {
    ++faults_;
    gain_ = 0.0;
    ramping_in_ = true;
    last_force_n_ = last_torque_nm_ = 0.0;
    axial_pc_.reset();
    torque_pc_.reset();
    out.flags |= kFlagFault;
    return out;
  }

  // fade on a stale model or a silent instrument, starting from what the trainee last felt
  // (never from a possibly-garbage model); ramp back in once both are fine again
  const bool stale = model_stale(now_us);
  const bool silent = sample.received_us == 0 || now_us - sample.received_us > params_.instrument_timeout_ms * 1e3;
  if (stale) out.flags |= kFlagStale;
  double force_n = 0.0, torque_nm = 0.0;
  if (stale || silent) {
    const double old_gain = gain_;
    gain_ = std::max(0.0, gain_ - dt_s / std::max(params_.fade_ms * 1e-3, 1e-6));
    const double scale = old_gain > 0.0 ? gain_ / old_gain : 0.0;
    force_n = last_force_n_ * scale;
    torque_nm = last_torque_nm_ * scale;
    ramping_in_ = true;
    out.flags |= kFlagFaded;
  } else {
    if (ramping_in_) {
      gain_ = std::min(1.0, gain_ + dt_s / std::max(params_.ramp_in_ms * 1e-3, 1e-6));
      ramping_in_ = gain_ < 1.0;
      out.flags |= kFlagRamping;
    }
    force_n = raw.force_n * gain_;
    torque_nm = raw.torque_nm * gain_;
    if (has_model_ && params_.interpolation == Interpolation::kLocalModel) {
      out.axial_stiffness_n_per_m = model_.k_n_per_m * gain_;
      out.torsional_stiffness_nm_per_rad = model_.kt_nm_per_rad * gain_;
    }
  }

  // slew limit, then passivity (it may add damping), then the hard clamp has the last word
  force_n = slew(force_n, last_force_n_, params_.slew_n_per_s * dt_s);
  torque_nm = slew(torque_nm, last_torque_nm_, params_.slew_nm_per_s * dt_s);
  if (params_.passivity && !(stale || silent)) {
    force_n = axial_pc_.filter(force_n, sample.insertion_rate_m_per_s, dt_s, params_.peak_force_n);
    torque_nm = torque_pc_.filter(torque_nm, sample.rotation_rate_rad_per_s, dt_s, params_.peak_torque_nm);
    if (axial_pc_.last_damping() > 0 || torque_pc_.last_damping() > 0) out.flags |= kFlagDamped;
  }
  // a clamped axis has no spring: a device's spring would push past the clamp
  if (std::abs(force_n) > params_.peak_force_n) out.axial_stiffness_n_per_m = 0.0;
  if (std::abs(torque_nm) > params_.peak_torque_nm) out.torsional_stiffness_nm_per_rad = 0.0;
  force_n = clamp_abs(force_n, params_.peak_force_n, out.flags);
  torque_nm = clamp_abs(torque_nm, params_.peak_torque_nm, out.flags);

  last_force_n_ = out.axial_force_n = force_n;
  last_torque_nm_ = out.torque_nm = torque_nm;
  return out;
}

}  // namespace pcisim::haptics
