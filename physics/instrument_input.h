#pragma once
// What the instrument tells physics: the proximal end of the wire as the trainee holds it.
#include <cstdint>

namespace pcisim::physics {

struct InstrumentInput {
  double insertion_m = 0.0;   // wire length pushed past the introducer
  double rotation_rad = 0.0;  // cumulative twist at the proximal end
  double insertion_rate_m_per_s = 0.0;
  double rotation_rate_rad_per_s = 0.0;
  uint32_t buttons = 0;
};

}  // namespace pcisim::physics
