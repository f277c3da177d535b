#pragma once
// Safety and smoothing settings of the 1 kHz force loop (scene: "haptics").

namespace pcisim::haptics {

// how the 1 kHz loop fills the time between 30 Hz physics results
enum class Interpolation {
  kLocalModel,           // f0 + K (x - x0) + B v at the newest instrument sample, blended over blend_ms
  kZeroOrderHold,        // the newest physics force, held until the next one
  kLinearExtrapolation,  // the last two physics forces extended in time
};

struct HapticParams {
  Interpolation interpolation = Interpolation::kLocalModel;
  bool passivity = true;  // time-domain passivity observer/controller
  double passivity_max_damping_n_s_per_m = 200.0;
  double passivity_max_damping_nm_s_per_rad = 0.05;
  double peak_force_n = 4.0;            // |axial force| never exceeds this
  double peak_torque_nm = 0.02;         // |torque| never exceeds this
  double slew_n_per_s = 200.0;          // force may change at most this fast
  double slew_nm_per_s = 1.0;           // torque likewise
  double blend_ms = 5.0;                // a new model takes over over this long (no step)
  double fade_ms = 50.0;                // fade to zero on stale model, silent instrument or fault
  double ramp_in_ms = 200.0;            // ramp up on start and after a fault
  double instrument_timeout_ms = 50.0;  // no instrument sample for this long: fade
};

// throws std::invalid_argument naming the field ("haptics.peak_force_n must be ...") when a value
// is non-finite or out of range; ForceEvaluator checks its params with it
void validate(const HapticParams& params);

}  // namespace pcisim::haptics
