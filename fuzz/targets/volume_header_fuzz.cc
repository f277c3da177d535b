// libFuzzer: a MetaImage (PCISIM_FUZZ_NRRD undefined) or NRRD file, header and inline data,
// through the volume reader (NRRD: the 3-D reader and the 4-D sequence reader, each its own
// try). A refusal is a VolumeIoError; anything else is a finding.
#include <cstddef>
#include <cstdint>

#include "fuzz/targets/fuzz_file.h"
#include "anatomy/volume/volume_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const pcisim::fuzz::MemoryFile file(data, size);
  if (!file.ok()) return 0;
  try {
#ifdef PCISIM_FUZZ_NRRD
    (void)pcisim::anatomy::read_nrrd(file.path());
  } catch (const pcisim::anatomy::VolumeIoError&) {}
  try {
    (void)pcisim::anatomy::read_nrrd_sequence(file.path());
#else
    (void)pcisim::anatomy::read_metaimage(file.path());
#endif
  } catch (const pcisim::anatomy::VolumeIoError&) {}
  return 0;
}
