// libFuzzer: a scene file's text through the scene parser (server/scene). A refusal is a
// json::JsonError naming the path; anything else (a crash, a hang, UB, a leak) is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "server/scene/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    (void)pcisim::server::parse_scene(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json");
  } catch (const std::exception&) {}
  return 0;
}
