#pragma once
// Decoding that never trusts the sender: wrong fingerprint, truncated data and non-finite
// fields all count as a bad message.
#include <cstdint>
#include <lcm/lcm-cpp.hpp>

#include "pcisim_lcm/force_command_t.hpp"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/probe_state_t.hpp"
#include "pcisim_lcm/session_command_t.hpp"
#include "pcisim_lcm/session_metrics_t.hpp"
#include "pcisim_lcm/sim_status_t.hpp"
#include "pcisim_lcm/us_frame_t.hpp"
#include "pcisim_lcm/wire_state_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"

namespace pcisim::protocol {

// true when every floating-point field is finite, sizes agree with their arrays, and every name
// (a branch's, an effect's) is well-formed UTF-8 without NUL: names reach JSON texts and logs
bool is_well_formed(const pcisim_lcm::instrument_state_t& m);
bool is_well_formed(const pcisim_lcm::force_command_t& m);
bool is_well_formed(const pcisim_lcm::session_command_t& m);
bool is_well_formed(const pcisim_lcm::wire_state_t& m);
bool is_well_formed(const pcisim_lcm::sim_status_t& m);
// finite, counts and times not negative (target_reached_s: -1 until reached)
bool is_well_formed(const pcisim_lcm::session_metrics_t& m);
bool is_well_formed(const pcisim_lcm::xray_frame_t& m);
// and for the probe: a position within 10 m of the scene's origin, a unit quaternion (norm within
// 1 %: a pose, not a scaling; the receiver normalises it), a depth of 0 (the scene's) or 1-500 mm
// and a gain within +-60 dB (protocol/probe_ranges.h)
bool is_well_formed(const pcisim_lcm::probe_state_t& m);
// an ultrasound frame: a known format and geometry, width x height bytes (at most 4096 x 4096),
// beam and lateral unit and perpendicular (within 1e-3), finite fields, and the renderer's ranges:
// depth (0, 300] mm, gain within +-60 dB, frequency 1-20 MHz; linear: width_mm (0, 200];
// curvilinear: fan angle (0, 150] deg, radius of curvature (0, 200] mm (the other geometry's
// fields are not read, only kept finite and not negative)
bool is_well_formed(const pcisim_lcm::us_frame_t& m);

// CMD_CONTRAST: the volume a command may name (0.5-30 ml); outside it, or 0, the scene's volume is
// injected. One rule for the server, which injects, and the clients that count what was used.
inline bool is_commanded_contrast_volume(double ml) {
  return ml >= 0.5 && ml <= 30.0;
}  // false for NaN

// decodes data into out; false on a wrong fingerprint, truncation, trailing bytes, a bad length or
// count, or a bad field. The one path every handler in every program decodes through: whatever
// the generated decoder does with hostile bytes (cmake/harden_decoders.cmake bounds it before it
// allocates), nothing it throws leaves here.
template <class Message>
bool decode_checked(const void* data, int64_t size, Message& out) noexcept {
  if (data == nullptr || size < 0 || size > INT32_MAX) return false;
  try {
    const int used = out.decode(data, 0, static_cast<int>(size));
    return used >= 0 && used == size && is_well_formed(out);
  } catch (...) {  // std::length_error, std::bad_alloc: a message, not the process, is lost
    return false;
  }
}

template <class Message>
bool decode_checked(const lcm::ReceiveBuffer& rbuf, Message& out) noexcept {
  return decode_checked(rbuf.data, static_cast<int64_t>(rbuf.data_size), out);
}

}  // namespace pcisim::protocol
