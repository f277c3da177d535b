// libFuzzer: a trainee script's text (clients/bridge/trainee_script) and a few reads of it.
#include <cstddef>
#include <cstdint>
#include <string>

#include "clients/bridge/trainee_script.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const auto s =
        pcisim::clients::TraineeScript::parse(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json");
    for (double t : {0.0, 1.0, 1e3}) (void)s.sample(t);
  } catch (const std::exception&) {}
  return 0;
}
