#pragma once
// The built-in trainee's session (clients/bridge/trainee_script.cc) with the turn toward the LAD,
// as instrument input over time: what the benchmarks drive the wire with; and the default scene's
// physics they drive it in.
#include <algorithm>
#include <numbers>

#include "physics/instrument_input.h"
#include "physics/world_spec.h"

namespace pcisim::bench {

inline double ramp(double t, double at_s, double over_s, double amount) {
  return t <= at_s ? 0.0 : amount * std::min((t - at_s) / over_s, 1.0);
}

inline physics::InstrumentInput session_at(double t) {
  physics::InstrumentInput in;
  in.insertion_m = 1e-3 * (ramp(t, 0.5, 3.0, 8.0) + ramp(t, 7.0, 10.0, 50.0) - ramp(t, 17.5, 1.0, 5.0));
  in.rotation_rad = ramp(t, 4.0, 2.0, 90.0 * std::numbers::pi / 180.0);
  in.insertion_rate_m_per_s = (t > 0.5 && t < 3.5 ? 8e-3 / 3.0 : 0.0) + (t > 7.0 && t < 17.0 ? 5e-3 : 0.0) -
                              (t > 17.5 && t < 18.5 ? 5e-3 : 0.0);
  in.rotation_rate_rad_per_s = t > 4.0 && t < 6.0 ? 0.25 * std::numbers::pi : 0.0;
  return in;
}

inline constexpr double kSessionS = 19.5;

// the default scene's physics (scenes/default.json's effects at their defaults) at 30 Hz; without
// `beating` the same scene with heart_beat and vessel_motion left out
inline physics::WorldSpec default_scene_spec(bool beating = true) {
  physics::WorldSpec s;
  s.step_s = 1.0 / 30.0;
  if (beating) {
    s.heart_beat = physics::HeartBeatParams{};
    s.vessel_motion = physics::VesselMotionParams{};
  }
  s.guidewire = physics::GuidewireParams{};
  s.vessel_contact = physics::VesselContactParams{};
  s.friction = physics::FrictionParams{};
  s.blood_flow = physics::BloodFlowParams{};
  return s;
}

}  // namespace pcisim::bench
