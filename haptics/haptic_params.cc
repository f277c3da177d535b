#include "haptics/haptic_params.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace pcisim::haptics {
namespace {

void require(bool ok, const char* field, const char* rule, double value) {
  if (!ok)
    throw std::invalid_argument(std::string("haptics.") + field + " must be " + rule + ", got " +
                                std::to_string(value));
}
bool finite_in(double x, double lo, double hi) {
  return std::isfinite(x) && x >= lo && x <= hi;
}

}  // namespace

void validate(const HapticParams& p) {
  // the safety layers compare against these, so a NaN here would pass a NaN to the motors
  require(finite_in(p.peak_force_n, 0.0, 20.0), "peak_force_n", "in [0, 20] N", p.peak_force_n);
  require(finite_in(p.peak_torque_nm, 0.0, 1.0), "peak_torque_nm", "in [0, 1] N m", p.peak_torque_nm);
  require(std::isfinite(p.slew_n_per_s) && p.slew_n_per_s > 0.0, "slew_n_per_s", "finite and > 0", p.slew_n_per_s);
  require(std::isfinite(p.slew_nm_per_s) && p.slew_nm_per_s > 0.0, "slew_nm_per_s", "finite and > 0", p.slew_nm_per_s);
  require(finite_in(p.blend_ms, 0.0, 1e4), "blend_ms", "in [0, 1e4]", p.blend_ms);
  require(std::isfinite(p.fade_ms) && p.fade_ms > 0.0, "fade_ms", "finite and > 0", p.fade_ms);
  require(std::isfinite(p.ramp_in_ms) && p.ramp_in_ms > 0.0, "ramp_in_ms", "finite and > 0", p.ramp_in_ms);
  require(std::isfinite(p.instrument_timeout_ms) && p.instrument_timeout_ms > 0.0, "instrument_timeout_ms",
          "finite and > 0", p.instrument_timeout_ms);
  require(finite_in(p.passivity_max_damping_n_s_per_m, 0.0, 1e6), "passivity_max_damping_n_s_per_m", "in [0, 1e6]",
          p.passivity_max_damping_n_s_per_m);
  require(finite_in(p.passivity_max_damping_nm_s_per_rad, 0.0, 1e3), "passivity_max_damping_nm_s_per_rad",
          "in [0, 1e3]", p.passivity_max_damping_nm_s_per_rad);
}

}  // namespace pcisim::haptics
