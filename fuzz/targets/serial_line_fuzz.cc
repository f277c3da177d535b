// libFuzzer: one line from the instrument's encoder box (clients/bridge/serial_device).
#include <cstddef>
#include <cstdint>
#include <string>

#include "clients/bridge/serial_device.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  pcisim::clients::EncoderLine line;
  (void)pcisim::clients::parse_encoder_line(std::string(reinterpret_cast<const char*>(data), size), line);
  return 0;
}
