#pragma once
// One instrument box's profile (docs/serial-protocol.md, "Device profile"): how its encoder counts
// become the wire's insertion and rotation, and how the server's force becomes its actuators'
// set-points — scale (a negative scale flips the sign), the box's limits and a low-pass filter —
// so one server serves different boxes. Read from JSON and validated at start: every error names
// the file and the JSON path. `pcisim-bridge --profile FILE`.
#include <string>

#include "clients/bridge/force_line.h"
#include "clients/bridge/serial_device.h"

namespace pcisim::clients {

// the server's force on its way to the box: times the scales, clamped to the limits, then a
// first-order low-pass (0 Hz: none). Zero in a fault is never filtered: it is sent at once
// the shaping's ranges, the one source for the profile reader and validate()
inline constexpr double kMaxForceScale = 100.0;
inline constexpr double kMinForceLimit = 1e-3;  // N or N mm
inline constexpr double kMinFilterHz = 1.0, kMaxFilterHz = 1e4;

struct ForceShaping {
  double axial_scale = 1.0, torque_scale = 1.0;  // [-100, 100]
  double max_axial_n = 20.0;                     // (0, 20]: the force line's range at most
  double max_torque_nmm = 1000.0;                // (0, 1000]
  double filter_hz = 0.0;                        // 0 or [1, 10000]
};

// throws std::invalid_argument ("force shaping: ...") for a zero or non-finite scale, a limit
// outside the force line's range, or a filter below 1 Hz (not 0)
void validate(const ForceShaping& shaping);

struct DeviceProfile {
  std::string name = "default";
  SerialCalibration calibration;
  ForceShaping force;
};

// throws std::runtime_error "<source>: <json path>: expected ..., got ..."
DeviceProfile parse_device_profile(const std::string& text, const std::string& source);
DeviceProfile load_device_profile(const std::string& path);  // a regular file of at most 64 KiB
// the profile a bridge without --profile uses (documented defaults)
const std::string& default_device_profile_text();

// the shaping as a running filter: one step per bridge tick. Allocates nothing
class ForceShaper {
 public:
  explicit ForceShaper(const ForceShaping& shaping) : shaping_(shaping) {}
  // a set-point to render after dt_s (the tick); `zero`: a fault, sent as zero at once and the
  // filter restarted from zero
  ForceSetpoint step(const ForceSetpoint& in, double dt_s, bool zero);

 private:
  ForceShaping shaping_;
  ForceSetpoint state_;
};

}  // namespace pcisim::clients
