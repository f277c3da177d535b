#pragma once
// The ITK side of the DICOM reader, in plain standard types: ITK 5.2 bundles its own Eigen 3.3,
// which must never meet the system Eigen pcisim uses in one translation unit, so only
// itk_dicom_io.cc includes ITK. Errors throw std::runtime_error with ITK's description.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace pcisim::anatomy::itk_io {

// SeriesInstanceUIDs of the DICOM files in a folder
std::vector<std::string> series_uids(const std::string& folder);
// the files of one series (ITK's order; the caller sorts by position)
std::vector<std::string> series_files(const std::string& folder, const std::string& uid);
// the string value of each tag ("gggg|eeee") in a file's header, "" when absent
std::vector<std::string> read_tags(const std::string& file, const std::vector<std::string>& tags);
// the voxels of these files stacked in this order, rescaled to HU (slope and intercept)
std::vector<float> read_voxels(const std::vector<std::string>& files, std::array<int64_t, 3>* dims);

}  // namespace pcisim::anatomy::itk_io
