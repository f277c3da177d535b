// libFuzzer: a centerline file (vessels.json, anatomy/vessel/vessel_tree_json).
#include <cstddef>
#include <cstdint>
#include <stdexcept>

#include "fuzz/targets/fuzz_file.h"
#include "anatomy/vessel/vessel_tree_json.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const pcisim::fuzz::MemoryFile file(data, size);
  if (!file.ok()) return 0;
  try {
    (void)pcisim::anatomy::read_vessel_tree_json(file.path());
  } catch (const std::exception&) {}
  return 0;
}
