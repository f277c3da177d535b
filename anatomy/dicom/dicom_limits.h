#pragma once
// The bounds on what a DICOM series may hold (issue #38), defined once: the header walk
// (dicom_precheck) and the series reader (dicom_series) refuse anything beyond them before GDCM,
// ITK or a matrix sees the number. docs/security.md states them.
#include <cstdint>

namespace pcisim::anatomy::dicom {

// one file, read whole by the header walk: a 4096 x 4096 slice of 32-bit pixels is 64 MiB
inline constexpr int64_t kMaxFileBytes = int64_t{1} << 30;
// sequences inside sequences: real files nest 3 or 4 deep; bounds the walk's recursion
inline constexpr int kMaxSequenceDepth = 16;
// files examined in a series folder, so also the slices of a series: a 4-D CT of 20 phases x 1000
// slices is 20 000
inline constexpr int64_t kMaxFolderFiles = 65536;
// NumberOfFrames (0028,0008): the pixel data length is checked against rows x columns x frames
inline constexpr int64_t kMaxFrames = 65536;
// ImagePositionPatient (0020,0032), SliceThickness, SpacingBetweenSlices: 100 m; a scanner's
// patient coordinates are within a few metres, and |x| this small keeps every product finite
inline constexpr double kMaxPositionMm = 1e5;
// PixelSpacing (0028,0030) and the spacing between slices: 1 um (finer than any micro-CT) to 10 cm
// (coarser than any CT or MR slice); so no voxel of 1e300 mm or of 0
inline constexpr double kMinSpacingMm = 1e-3;
inline constexpr double kMaxSpacingMm = 100.0;
// ImageOrientationPatient (0020,0037): each direction's length within this of 1 (cosines are
// written with 4 or more decimals), and the cosine between them at most kMaxOrientationCosine
inline constexpr double kOrientationLengthTolerance = 1e-2;
inline constexpr double kMaxOrientationCosine = 1e-3;
// RescaleSlope (0028,1053) and RescaleIntercept (0028,1052): HU are within a few thousand; this keeps
// slope x 2^32 + intercept finite in float
inline constexpr double kMaxRescale = 1e6;

}  // namespace pcisim::anatomy::dicom
