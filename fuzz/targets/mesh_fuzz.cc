// libFuzzer: a mesh file a user brings (anatomy/mesh/mesh_io): STL, PLY or OBJ by
// PCISIM_FUZZ_MESH_FORMAT. A refusal (MeshIoError naming the file) is the expected answer;
// anything else (a crash, a hang, UB, a huge allocation, a leak) is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "anatomy/mesh/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    (void)pcisim::anatomy::parse_mesh("fuzz", PCISIM_FUZZ_MESH_FORMAT, bytes);
  } catch (const pcisim::anatomy::MeshIoError&) {}
  return 0;
}
