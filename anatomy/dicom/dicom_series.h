#pragma once
// A CT series (or a cine: 3-D + time) from a folder of DICOM files (ITK's GDCM image IO): HU
// (rescale slope and intercept applied), geometry in LPS millimetres as the files state it. Before
// any voxel is read, every slice's position is checked along the slice normal: a missing slice or
// uneven spacing is refused naming the file, as are mixed orientations or pixel sizes. Every file
// in the folder is first walked by our own header check (dicom_precheck.h) and its numbers
// bounded (dicom_limits.h) before GDCM or ITK sees it: in the folder, a file that does not start
// with the 128-byte preamble and "DICM" is a stray file and skipped, as is a DICOMDIR that passes
// the walk; any other file that fails refuses the series, naming the file and the tag.
#include <string>
#include <vector>

#include "anatomy/dicom/dicom_error.h"
#include "anatomy/volume/volume.h"

namespace pcisim::anatomy {

// the one series in `folder`, or the one with this SeriesInstanceUID when there are several.
// int16 voxels when every HU fits, else float32. Throws DicomError "<folder or file>: <what>".
Volume read_dicom_series(const std::string& folder, const std::string& series_uid = "");

// a DICOM cine (3-D + time: cine MRI, 4-D CT): one series whose images cover several temporal
// positions, each a stack of slices. One Volume per time point in time order, each built as
// read_dicom_series builds its volume. Images are grouped by Temporal Position Identifier
// (0020,0100) when the files give it, else by Trigger Time (0018,1060) (the same value within a
// time point), groups taken in that value's order; every image must give the key. Before any voxel
// is read each time point's stack is checked as read_dicom_series checks a series, and must have
// frame 0's slice count, orientation, pixel and slice spacing and first-slice position (refusals
// name the time point, e.g. "<folder>: temporal position 3: 7 slices, temporal position 1 has 8").
// Also refused: one time point ("a 3-D series, not a cine"), one slice a time point (a 2-D cine),
// multi-frame files, a whole sequence over the volume readers' voxel cap. All frames int16, or all
// float32 when any needs it. Throws DicomError "<folder or file>: <what>".
std::vector<Volume> read_dicom_cine(const std::string& folder, const std::string& series_uid = "");

}  // namespace pcisim::anatomy
