#pragma once
// Writes one CT slice as a DICOM file through ITK, for the DICOM reader's tests. Plain standard
// types only: ITK's bundled Eigen must not meet the system Eigen in one translation unit.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace pcisim::anatomy::testing {

struct DicomSlice {
  std::string file;
  std::string series_uid, study_uid;
  int instance = 1;
  std::array<double, 3> position_mm{};       // ImagePositionPatient
  std::array<double, 6> orientation{};       // ImageOrientationPatient: row then column direction
  std::array<double, 2> pixel_spacing_mm{};  // PixelSpacing: between rows, between columns
  double slice_thickness_mm = 1.0;
  double rescale_intercept = -1024;  // stored = HU - intercept (slope 1)
  // a cine's time tags, left out when negative: TemporalPositionIdentifier (0020,0100) and
  // TriggerTime (0018,1060, ms)
  int temporal_position = -1;
  double trigger_time_ms = -1;
};

// hu: columns x rows, row-major (column index fastest)
void write_dicom_slice(const DicomSlice& s, int columns, int rows, const std::vector<int16_t>& hu);

}  // namespace pcisim::anatomy::testing
