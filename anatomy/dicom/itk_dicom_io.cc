#include "anatomy/dicom/itk_dicom_io.h"

#include <itkGDCMImageIO.h>
#include <itkGDCMSeriesFileNames.h>
#include <itkImage.h>
#include <itkImageSeriesReader.h>
#include <itkMetaDataObject.h>

#include <iostream>
#include <streambuf>
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

// std::cerr muted while `f` runs. Listing a cine's files, GDCM's own ordering by position fails
// (each position repeats once a time point) and GDCM prints "position is not unique" to std::cerr
// for every image before falling back to instance numbers; the callers sort the files themselves
// and say what is wrong in their exceptions. (GDCM's trace switch, gdcm::Trace, would need GDCM's
// headers and libraries, which ITK's targets do not pass on.)
template <class F>
auto cerr_muted(F&& f) {
  struct Null : std::streambuf {
    int overflow(int c) override { return traits_type::not_eof(c); }
  };
  static Null null;
  struct Restore {
    std::streambuf* was = std::cerr.rdbuf(&null);
    ~Restore() { std::cerr.rdbuf(was); }
  } restore;
  return f();
}

itk::GDCMSeriesFileNames::Pointer names_in(const std::string& folder) {
  auto names = itk::GDCMSeriesFileNames::New();
  names->SetUseSeriesDetails(false);
  names->SetDirectory(folder);
  return names;
}

}  // namespace

std::vector<std::string> series_uids(const std::string& folder) {
  return itk_call([&] { return cerr_muted([&] { return names_in(folder)->GetSeriesUIDs(); }); });
}

std::vector<std::string> series_files(const std::string& folder, const std::string& uid) {
  return itk_call([&] { return cerr_muted([&] { return names_in(folder)->GetFileNames(uid); }); });
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

void read_voxels(const std::vector<std::string>& files, const VoxelSink& take) {
  // ITK's exceptions become runtime_error; the caller's own (thrown by take) pass through
  auto reader = itk::ImageSeriesReader<itk::Image<float, 3>>::New();
  itk_call([&] {
    reader->SetImageIO(itk::GDCMImageIO::New());
    reader->SetFileNames(files);
    reader->Update();
    return 0;
  });
  const auto* image = reader->GetOutput();
  const auto size = image->GetLargestPossibleRegion().GetSize();
  take({int64_t(size[0]), int64_t(size[1]), int64_t(size[2])}, image->GetBufferPointer());
}

}  // namespace pcisim::anatomy::itk_io
