#pragma once
// A CT series from a folder of DICOM files (ITK's GDCM image IO): HU (rescale slope and
// intercept applied), geometry in LPS millimetres as the files state it. Before any voxel is
// read, every slice's position is checked along the slice normal: a missing slice or uneven
// spacing is refused naming the file, as are mixed orientations or pixel sizes.
#include <stdexcept>
#include <string>

#include "anatomy/volume/volume.h"

namespace pcisim::anatomy {

struct DicomError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// the one series in `folder`, or the one with this SeriesInstanceUID when there are several.
// int16 voxels when every HU fits, else float32. Throws DicomError "<folder or file>: <what>".
Volume read_dicom_series(const std::string& folder, const std::string& series_uid = "");

}  // namespace pcisim::anatomy
