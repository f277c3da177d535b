#pragma once
// Our own walk over a DICOM file's header, before GDCM sees the file (issue #38: GDCM 3.0 asserts,
// SIGABRT, on files a user can write: a file that is only the preamble, an element length past
// the end, a position of 1e308 that reaches ITK's matrices). Only what GDCM reads without its
// repair heuristics passes:
// - the 128-byte preamble and "DICM", then the File Meta group (0002) in explicit VR little
//   endian, starting with its group length (0002,0000), which must count the group exactly;
// - Transfer Syntax UID (0002,0010): Implicit VR Little Endian (1.2.840.10008.1.2) or Explicit VR
//   Little Endian (1.2.840.10008.1.2.1); any other (big endian, deflated, JPEG, JPEG-LS, JPEG 2000,
//   RLE, video) is refused by name;
// - Media Storage SOP Class UID (0002,0002): CT, MR or secondary capture image storage, the same
//   as SOPClassUID (0008,0016); or a DICOMDIR (which holds no image: the series listing skips it);
// - every data element, in sequences and items too: tags ascending in each data set, a known VR
//   (explicit), an even length that fits in the bytes that remain of the file, its item or its
//   sequence, fixed-size VRs a whole number of values, the elements GDCM reads as a typed attribute
//   of their dictionary VR (and length, for one binary value), undefined lengths only for sequences (SQ,
//   UN, or implicit) with their items and delimitation tags, sequences nested at most
//   kMaxSequenceDepth deep;
// - the top-level numbers GDCM and ITK compute with, bounded (dicom_limits.h): Rows, Columns,
//   NumberOfFrames, SamplesPerPixel 1, BitsAllocated 8/16/32, BitsStored, HighBit,
//   PixelRepresentation, PhotometricInterpretation MONOCHROME1/2, ImagePositionPatient,
//   ImageOrientationPatient, PixelSpacing, SliceThickness, SpacingBetweenSlices, RescaleSlope and
//   RescaleIntercept; and Pixel Data (7FE0,0010), native (OB/OW, a defined length), exactly
//   Rows x Columns x NumberOfFrames x BitsAllocated/8 bytes;
// - refused outright, as GDCM asserts on their malformed forms: overlays (60xx) and curves (50xx),
//   lookup tables, icon images, retired ACR-NEMA elements, command groups (0000).
// Every refusal: DicomError "<file>: <keyword> (gggg,eeee): <what>".
#include <cstdint>
#include <string>
#include <string_view>

#include "anatomy/dicom/dicom_error.h"

namespace pcisim::anatomy::dicom {

// what the walk learned of a file that passed
struct CheckedFile {
  std::string transfer_syntax_uid;
  std::string series_uid;  // SeriesInstanceUID (0020,000E), "" when absent
  bool dicomdir = false;   // a DICOMDIR: no image
  int64_t rows = 0, columns = 0, frames = 1, bits_allocated = 0;
};

// the 128-byte preamble then "DICM": a file without them is not a DICOM file (a listing skips it)
bool has_dicom_magic(std::string_view bytes);

// the walk over a file's bytes; throws DicomError naming `file` (also a file without the magic)
CheckedFile precheck_dicom(const std::string& file, std::string_view bytes);
// the same over the file at `path`, read through json::read_regular_file (at most kMaxFileBytes)
CheckedFile precheck_dicom_file(const std::string& path);

}  // namespace pcisim::anatomy::dicom
