#include "anatomy/dicom/itk_dicom_io.h"

#include <itkGDCMImageIO.h>
#include <itkImage.h>
#include <itkImageSeriesReader.h>
#include <itkMetaDataObject.h>

#include <stdexcept>

#include "anatomy/dicom/dicom_precheck.h"

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

// the header walk first: GDCM never opens a file that fails it (nor a DICOMDIR: no image)
void checked(const std::string& file) {
  if (dicom::precheck_dicom_file(file).dicomdir) throw DicomError(file + ": a DICOMDIR, not an image");
}

}  // namespace

std::vector<std::string> read_tags(const std::string& file, const std::vector<std::string>& tags) {
  checked(file);
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
  for (const auto& f : files) checked(f);
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
