#include "clients/bridge/force_gate.h"

#include <algorithm>
#include <cmath>

#include "pcisim_lcm/force_command_t.hpp"

namespace pcisim::clients {

ForceGateState gate_force(const ForceGateInput& in, ForceSetpoint* out) {
  using F = pcisim_lcm::force_command_t;
  *out = ForceSetpoint{};
  if (!in.device_ok) return ForceGateState::kDeviceFault;
  if (in.last_command_ns < 0) return ForceGateState::kNoCommand;
  if (in.now_ns - in.last_command_ns > kServerSilentNs) return ForceGateState::kServerSilent;
  if (in.flags & F::FLAG_FAULT) return ForceGateState::kFlaggedFault;
  if (in.flags & F::FLAG_STALE) return ForceGateState::kFlaggedStale;
  if (!std::isfinite(in.axial_n) || !std::isfinite(in.torque_nmm) || !std::isfinite(in.axial_stiffness_n_per_mm) ||
      !std::isfinite(in.torsional_stiffness_nmm_per_rad))
    return ForceGateState::kNotFinite;
  out->axial_n = in.axial_n;
  out->torque_nmm = in.torque_nmm;
  // a negative spring would push the hand on: none
  out->axial_stiffness_n_per_mm = std::max(in.axial_stiffness_n_per_mm, 0.0);
  out->torsional_stiffness_nmm_per_rad = std::max(in.torsional_stiffness_nmm_per_rad, 0.0);
  out->sample_seq = in.instrument_seq;
  return ForceGateState::kRendering;
}

const char* describe(ForceGateState state) {
  switch (state) {
    case ForceGateState::kRendering:
      return "rendering the server's force";
    case ForceGateState::kNoCommand:
      return "zero force: no force command yet";
    case ForceGateState::kServerSilent:
      return "zero force: the server is silent";
    case ForceGateState::kFlaggedStale:
      return "zero force: the server flags its force stale";
    case ForceGateState::kFlaggedFault:
      return "zero force: the server flags a fault";
    case ForceGateState::kNotFinite:
      return "zero force: a non-finite force command";
    case ForceGateState::kDeviceFault:
      return "zero force: the device is in fault";
  }
  return "?";
}

}  // namespace pcisim::clients
