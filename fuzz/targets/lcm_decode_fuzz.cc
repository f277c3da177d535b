// libFuzzer: one LCM message type (PCISIM_FUZZ_TYPE) through the one decode path every handler
// uses. Any bytes must give true or false: no crash, no exception, no allocation by a claimed size.
#include <cstddef>
#include <cstdint>

#include "protocol/message_checks.h"

#define PCISIM_STR2(x) #x
#define PCISIM_STR(x) PCISIM_STR2(x)
// (not formatted: spaces around the slash would enter the header name)
// clang-format off
#include PCISIM_STR(pcisim_lcm/PCISIM_FUZZ_TYPE.hpp)
// clang-format on

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  pcisim_lcm::PCISIM_FUZZ_TYPE message;
  (void)pcisim::protocol::decode_checked(data, static_cast<int64_t>(size), message);
  return 0;
}
