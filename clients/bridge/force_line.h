#pragma once
// The force the bridge hands an instrument box (docs/serial-protocol.md, "Force out"): one ASCII
// line per bridge tick,
//     F <axial_mN> <torque_uNm> <seq>
// integers, rounded half away from zero, clamped into the line's ranges; a non-finite set-point
// is sent as 0. The box applies a line until the next one, and zero once no line came for 50 ms
// (its watchdog; BoxSimulator keeps the same contract).
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace pcisim::clients {

// what a device renders this tick: the server's force, or zero in any fault (force_gate.h)
struct ForceSetpoint {
  double axial_n = 0.0;     // positive resists insertion
  double torque_nmm = 0.0;  // positive resists positive rotation
  // the force's rise with feed and twist about the sample it answers (>= 0): a device that
  // renders a spring centres it there. The force line does not carry them
  double axial_stiffness_n_per_mm = 0.0;
  double torsional_stiffness_nmm_per_rad = 0.0;
  int64_t sample_seq = -1;  // the bridge tick (instrument sample) the force answers; -1: none
};

// the line's ranges (a box clamps to its own actuator's limits after these)
inline constexpr int64_t kMaxAxialMilliNewton = 20000;          // 20 N
inline constexpr int64_t kMaxTorqueMicroNewtonMetre = 1000000;  // 1 N m
inline constexpr size_t kForceLineMaxBytes = 64;
inline constexpr double kBoxWatchdogS = 0.050;

// the line for `f`, ending in '\n', in buf (kForceLineMaxBytes); returns its length. Allocates nothing
size_t format_force_line(const ForceSetpoint& f, int64_t seq, char* buf);

struct ForceLine {
  int64_t axial_mn = 0, torque_unm = 0, seq = 0;
};
// a box's reading of one line (without its '\n'; a '\r' before it is accepted): false for
// anything but a force line within the ranges
bool parse_force_line(std::string_view line, ForceLine& out);

}  // namespace pcisim::clients
