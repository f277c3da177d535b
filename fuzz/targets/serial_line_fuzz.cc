// libFuzzer: one line on the instrument box's serial port, both ways (clients/bridge/serial_device,
// clients/bridge/force_line): the bridge's reading of an encoder line and a box's reading of a
// force line; a force line that parses must come back unchanged through the bridge's formatting.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "clients/bridge/force_line.h"
#include "clients/bridge/serial_device.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  pcisim::clients::EncoderLine line;
  (void)pcisim::clients::parse_encoder_line(text, line);
  pcisim::clients::ForceLine f;
  if (pcisim::clients::parse_force_line(text, f)) {
    char buf[pcisim::clients::kForceLineMaxBytes];
    const size_t n = pcisim::clients::format_force_line({f.axial_mn * 1e-3, f.torque_unm * 1e-3}, f.seq, buf);
    pcisim::clients::ForceLine back;
    if (n == 0 || !pcisim::clients::parse_force_line(std::string(buf, n - 1), back) || back.axial_mn != f.axial_mn ||
        back.torque_unm != f.torque_unm || back.seq != f.seq)
      std::abort();
  }
  return 0;
}
