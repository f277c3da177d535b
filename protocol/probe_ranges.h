#pragma once
// What a probe_state_t may say: one rule for the decoder (message_checks.cc), which refuses the
// rest, and for whoever writes one (the bridge's probe script), which refuses it earlier.
#include <cmath>

namespace pcisim::protocol {

inline constexpr double kProbeMaxDistanceMm = 1e4;  // from the scene's origin: 10 m
inline constexpr double kProbeMinDepthMm = 1.0, kProbeMaxDepthMm = 500.0;
inline constexpr double kProbeMaxGainDb = 60.0;
inline constexpr double kProbeQuaternionNormTolerance = 0.01;  // a pose, not a scaling

// within reach of the scene's origin; false for NaN
inline bool is_probe_position_mm(double x, double y, double z) {
  return x * x + y * y + z * z <= kProbeMaxDistanceMm * kProbeMaxDistanceMm;
}
// 0 asks for the scene's depth; asked for, at least 1 mm; false for NaN
inline bool is_probe_depth_mm(double mm) {
  return mm == 0.0 || (mm >= kProbeMinDepthMm && mm <= kProbeMaxDepthMm);
}
inline bool is_probe_gain_db(double db) {
  return std::abs(db) <= kProbeMaxGainDb;
}

}  // namespace pcisim::protocol
