#pragma once
// The local force model: what physics hands the 1 kHz haptic loop every step.
// Between physics steps the haptic thread evaluates
//   axial force  f = f0 + K (x - x0) + B v      (x = insertion, v = insertion rate)
//   torque       t = t0 + Kt (q - q0) + Bt w    (q = rotation, w = rotation rate)
// f is the force resisting insertion (t the torque resisting twist), so with K, B >= 0 both the
// spring and the damper oppose the motion. DESIGN.md writes "- B v" next to "+ K (x - x0)"; read
// in one sign convention that damper would feed energy in, so the passive reading is used here.
// Plain data so haptics depends on this header only, never on physics internals.
#include <cstdint>

namespace pcisim::physics {

struct LocalForceModel {
  int64_t made_utime = 0;      // physics time stamp of the step that produced it (µs)
  int64_t valid_for_us = 0;    // evaluate no longer than this after made_utime; 0 = invalid model
  double x0_m = 0.0;           // insertion the model was linearised at
  double f0_n = 0.0;           // axial force at x0 (positive resists insertion)
  double k_n_per_m = 0.0;      // d(force)/d(insertion), >= 0
  double b_n_s_per_m = 0.0;    // damping along insertion, >= 0 (resists the insertion rate)
  double q0_rad = 0.0;         // rotation the model was linearised at
  double t0_nm = 0.0;          // torque at q0
  double kt_nm_per_rad = 0.0;  // d(torque)/d(rotation), >= 0
  double bt_nm_s_per_rad = 0.0;
};

}  // namespace pcisim::physics
