// libFuzzer: what a browser sends the remote gateway before it is let in: the HTTP request
// target (path, query parameters such as token and fps) and the Authorization header.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "clients/remote/request_target.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  (void)pcisim::remote::target_path(text);
  for (const char* key : {"token", "fps", ""}) (void)pcisim::remote::query_param(text, key);
  (void)pcisim::remote::bearer_token(text);
  return 0;
}
