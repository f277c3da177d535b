#pragma once
// The ITK side of the DICOM reader, in plain standard types: ITK 5.2 bundles its own Eigen 3.3,
// which must never meet the system Eigen pcisim uses in one translation unit, so only
// itk_dicom_io.cc includes ITK. Errors throw std::runtime_error with ITK's description. Every file
// is walked by dicom::precheck_dicom_file (DicomError naming the file and tag) before GDCM opens it:
// GDCM asserts (SIGABRT) on malformed files. Listing a folder is dicom_series.cc's, through the
// same check (GDCM's own listing would open every file unchecked).
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace pcisim::anatomy::itk_io {

// the string value of each tag ("gggg|eeee") in a file's header, "" when absent
std::vector<std::string> read_tags(const std::string& file, const std::vector<std::string>& tags);
// the voxels of these files stacked in this order, rescaled to HU (slope and intercept), handed
// to `take` (dims, the x-fastest voxels) while ITK's image still holds them: the caller converts
// them straight into its own storage, so no third copy exists at once
using VoxelSink = std::function<void(const std::array<int64_t, 3>& dims, const float* voxels)>;
void read_voxels(const std::vector<std::string>& files, const VoxelSink& take);

}  // namespace pcisim::anatomy::itk_io
