// libFuzzer: a probe script's text (clients/bridge/probe_script) and a few samples of it, between,
// on and beyond its keyframes.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

#include "clients/bridge/probe_script.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const auto s =
        pcisim::clients::ProbeScript::parse(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json");
    for (double t : {-1.0, 0.0, 0.5, 1.0, s.duration_s(), 1e3, std::numeric_limits<double>::quiet_NaN()})
      (void)s.sample(t);
  } catch (const std::exception&) {}
  return 0;
}
