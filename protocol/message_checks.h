#pragma once
// Decoding that never trusts the sender: wrong fingerprint, truncated data and non-finite
// fields all count as a bad message.
#include <lcm/lcm-cpp.hpp>

#include "pcisim_lcm/force_command_t.hpp"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/session_command_t.hpp"
#include "pcisim_lcm/sim_status_t.hpp"
#include "pcisim_lcm/wire_state_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"

namespace pcisim::protocol {

// true when every floating-point field is finite and sizes agree with their arrays
bool is_well_formed(const pcisim_lcm::instrument_state_t& m);
bool is_well_formed(const pcisim_lcm::force_command_t& m);
bool is_well_formed(const pcisim_lcm::session_command_t& m);
bool is_well_formed(const pcisim_lcm::wire_state_t& m);
bool is_well_formed(const pcisim_lcm::sim_status_t& m);
bool is_well_formed(const pcisim_lcm::xray_frame_t& m);

// CMD_CONTRAST: the volume a command may name (0.5-30 ml); outside it, or 0, the scene's volume is
// injected. One rule for the server, which injects, and the clients that count what was used.
inline bool is_commanded_contrast_volume(double ml) { return ml >= 0.5 && ml <= 30.0; }  // false for NaN

// decodes rbuf into out; false on a wrong fingerprint, truncation, trailing bytes or a bad field
template <class Message>
bool decode_checked(const lcm::ReceiveBuffer& rbuf, Message& out) {
  const int used = out.decode(rbuf.data, 0, static_cast<int>(rbuf.data_size));
  return used >= 0 && static_cast<uint32_t>(used) == rbuf.data_size && is_well_formed(out);
}

}  // namespace pcisim::protocol
