#pragma once
// What force the bridge hands its device each tick: the server's last command while it is fresh
// and healthy, and zero — first, before anything else — in every fault: no command yet, the
// server silent for kServerSilentNs, a command flagged stale or faulted, a non-finite value, or
// the device itself in fault (docs/serial-protocol.md, "Force out"). With the bridge at 1 kHz a
// server fault reaches the box as zero force within about 21 ms, a silent box within the serial
// timeout (30 ms) and a tick; a box the bridge no longer reaches zeroes itself by its watchdog.
#include <cstdint>

#include "clients/bridge/force_line.h"

namespace pcisim::clients {

inline constexpr int64_t kServerSilentNs = 20'000'000;  // no force command for 20 ms

enum class ForceGateState {
  kRendering,
  kNoCommand,
  kServerSilent,
  kFlaggedStale,
  kFlaggedFault,
  kNotFinite,
  kDeviceFault
};

struct ForceGateInput {
  bool device_ok = false;
  int64_t now_ns = 0;
  int64_t last_command_ns = -1;  // when the last force command arrived; -1: none yet
  int32_t flags = 0;             // force_command_t.flags
  double axial_n = 0.0, torque_nmm = 0.0;
  double axial_stiffness_n_per_mm = 0.0, torsional_stiffness_nmm_per_rad = 0.0;
  int64_t instrument_seq = -1;  // force_command_t.instrument_seq
};

// the set-point (zero unless kRendering) and why
ForceGateState gate_force(const ForceGateInput& in, ForceSetpoint* out);
const char* describe(ForceGateState state);

}  // namespace pcisim::clients
