#pragma once
// Safety and smoothing settings of the 1 kHz force loop (scene: "haptics").

namespace pcisim::haptics {

struct HapticParams {
  double peak_force_n = 4.0;         // |axial force| never exceeds this
  double peak_torque_nm = 0.02;      // |torque| never exceeds this
  double slew_n_per_s = 200.0;       // force may change at most this fast
  double slew_nm_per_s = 1.0;        // torque likewise
  double blend_ms = 5.0;             // a new model takes over over this long (no step)
  double fade_ms = 50.0;             // fade to zero on stale model, silent instrument or fault
  double ramp_in_ms = 200.0;         // ramp up on start and after a fault
  double instrument_timeout_ms = 50.0;  // no instrument sample for this long: fade
};

}  // namespace pcisim::haptics
