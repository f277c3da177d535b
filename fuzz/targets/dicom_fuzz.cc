// libFuzzer: a DICOM file's bytes through the header walk (anatomy/dicom/dicom_precheck.h) that
// every file passes before GDCM may open it. A refusal is a DicomError; anything else is a finding.
// GDCM cannot be linked here (Debian's ITK headers refuse clang), so what the walk passes is run
// through GDCM by the anatomy tests: DicomFuzzCorpus.NeverAbortsGdcm replays this
// target's corpus (fuzz/corpus/dicom/) through ITK and GDCM.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "anatomy/dicom/dicom_precheck.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace dicom = pcisim::anatomy::dicom;
  try {
    (void)dicom::precheck_dicom("fuzz.dcm", std::string_view(reinterpret_cast<const char*>(data), size));
  } catch (const pcisim::anatomy::DicomError&) {}
  return 0;
}
