#pragma once
// What the instrument tells physics: the proximal end of the wire as the trainee holds it, or,
// in the soft-tissue scene, the ultrasound probe's pose.
#include <array>
#include <cstdint>

namespace pcisim::physics {

struct InstrumentInput {
  double insertion_m = 0.0;   // wire length pushed past the introducer
  double rotation_rad = 0.0;  // cumulative twist at the proximal end
  double insertion_rate_m_per_s = 0.0;
  double rotation_rate_rad_per_s = 0.0;
  uint32_t buttons = 0;
  // the probe (protocol/probe_state_t): the centre of its face and the rotation probe -> scene
  // (probe x lateral, z into the tissue). false until a probe sample has arrived: the scene's
  // start pose holds
  bool probe_present = false;
  std::array<double, 3> probe_position_m{};
  std::array<double, 4> probe_orientation_wxyz{1.0, 0.0, 0.0, 0.0};
  double probe_depth_mm = 0.0;  // imaging depth asked for (0: the scene's)
  double probe_gain_db = 0.0;   // added to the scene's gain
};

}  // namespace pcisim::physics
