#include "anatomy/dicom/itk_dicom_io.h"

#include <itkGDCMImageIO.h>
#include <itkGDCMSeriesFileNames.h>
#include <itkImage.h>
#include <itkImageSeriesReader.h>
#include <itkMetaDataObject.h>

#include <stdexcept>

namespace pcisim::anatomy::itk_io {
namespace {

template <class F>
auto itk_call(F&& f) {
  try {
    return f();
  } catch (const itk::ExceptionObject& e) {
    throw std::runtime_error(e.GetDescription());
  }
}

itk::GDCMSeriesFileNames::Pointer names_in(const std::string& folder) {
  auto names = itk::GDCMSeriesFileNames::New();
  names->SetUseSeriesDetails(false);
  names->SetDirectory(folder);
  return names;
}

}  // namespace

std::vector<std::string> series_uids(const std::string& folder) {
  return itk_call([&] { return names_in(folder)->GetSeriesUIDs(); });
}

std::vector<std::string> series_files(const std::string& folder, const std::string& uid) {
  return itk_call([&] { return names_in(folder)->GetFileNames(uid); });
}

std::vector<std::string> read_tags(const std::string& file, const std::vector<std::string>& tags) {
  return itk_call([&] {
    auto io = itk::GDCMImageIO::New();
    io->SetFileName(file);
    io->ReadImageInformation();
    std::vector<std::string> out;
    for (const auto& t : tags) {
      std::string value;
      itk::ExposeMetaData<std::string>(io->GetMetaDataDictionary(), t, value);
      out.push_back(value);
    }
    return out;
  });
}

std::vector<float> read_voxels(const std::vector<std::string>& files, std::array<int64_t, 3>* dims) {
  return itk_call([&] {
    using Image = itk::Image<float, 3>;
    auto reader = itk::ImageSeriesReader<Image>::New();
    reader->SetImageIO(itk::GDCMImageIO::New());
    reader->SetFileNames(files);
    reader->Update();
    const Image* image = reader->GetOutput();
    const auto size = image->GetLargestPossibleRegion().GetSize();
    *dims = {int64_t(size[0]), int64_t(size[1]), int64_t(size[2])};
    const float* px = image->GetBufferPointer();
    return std::vector<float>(px, px + (*dims)[0] * (*dims)[1] * (*dims)[2]);
  });
}

}  // namespace pcisim::anatomy::itk_io
