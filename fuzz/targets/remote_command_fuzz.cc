// libFuzzer: a WebSocket text message from a page, parsed as the gateway parses it (JSON), then
// checked as a session command against the gateway's limits.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "clients/remote/session_command_parser.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto msg = nlohmann::json::parse(data, data + size, nullptr, /*allow_exceptions=*/false);
  if (msg.is_discarded()) return 0;
  try {
    (void)pcisim::remote::parse_session_command(msg, pcisim::remote::CommandLimits{});
  } catch (const std::exception&) {}
  return 0;
}
