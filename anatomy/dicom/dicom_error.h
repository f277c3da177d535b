#pragma once
// The DICOM reader's one error type: "<folder or file>: <what>", a file's field named as
// "<keyword> (gggg,eeee)".
#include <stdexcept>

namespace pcisim::anatomy {

struct DicomError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace pcisim::anatomy
