#include "tests/anatomy/dicom/dicom_writer.h"

#include <fmt/format.h>
#include <itkGDCMImageIO.h>
#include <itkImage.h>
#include <itkImageFileWriter.h>
#include <itkMetaDataObject.h>

namespace pcisim::anatomy::testing {

void write_dicom_slice(const DicomSlice& s, int columns, int rows, const std::vector<int16_t>& hu) {
  // a one-slice 3-D image: ITK writes its origin, direction and spacing as the slice's geometry
  using Image = itk::Image<int16_t, 3>;
  auto image = Image::New();
  Image::SizeType size{{static_cast<itk::SizeValueType>(columns), static_cast<itk::SizeValueType>(rows), 1}};
  image->SetRegions(Image::RegionType(size));
  image->Allocate();
  Image::PointType origin;
  Image::SpacingType spacing;
  Image::DirectionType direction;
  const double* r = s.orientation.data();
  const double* c = s.orientation.data() + 3;
  const double n[3] = {r[1] * c[2] - r[2] * c[1], r[2] * c[0] - r[0] * c[2], r[0] * c[1] - r[1] * c[0]};
  for (int k = 0; k < 3; ++k) {
    origin[k] = s.position_mm[k];
    direction(k, 0) = r[k];
    direction(k, 1) = c[k];
    direction(k, 2) = n[k];
  }
  spacing[0] = s.pixel_spacing_mm[1];
  spacing[1] = s.pixel_spacing_mm[0];
  spacing[2] = s.slice_thickness_mm;
  image->SetOrigin(origin);
  image->SetSpacing(spacing);
  image->SetDirection(direction);
  int16_t* px = image->GetBufferPointer();
  for (size_t i = 0; i < hu.size(); ++i) px[i] = hu[i];

  auto& dict = image->GetMetaDataDictionary();
  itk::EncapsulateMetaData<std::string>(dict, "0008|0060", "CT");
  itk::EncapsulateMetaData<std::string>(dict, "0028|0004", "MONOCHROME2");
  itk::EncapsulateMetaData<std::string>(dict, "0008|0016", "1.2.840.10008.5.1.4.1.1.2");
  itk::EncapsulateMetaData<std::string>(dict, "0020|000d", s.study_uid);
  itk::EncapsulateMetaData<std::string>(dict, "0020|000e", s.series_uid);
  itk::EncapsulateMetaData<std::string>(dict, "0008|0018", fmt::format("{}.{}", s.series_uid, s.instance));
  itk::EncapsulateMetaData<std::string>(dict, "0020|0052", s.study_uid + ".9");
  itk::EncapsulateMetaData<std::string>(dict, "0020|0013", std::to_string(s.instance));
  itk::EncapsulateMetaData<std::string>(dict, "0028|1052", fmt::format("{}", s.rescale_intercept));
  itk::EncapsulateMetaData<std::string>(dict, "0028|1053", "1");
  if (s.temporal_position >= 0)
    itk::EncapsulateMetaData<std::string>(dict, "0020|0100", std::to_string(s.temporal_position));
  if (s.trigger_time_ms >= 0)
    itk::EncapsulateMetaData<std::string>(dict, "0018|1060", fmt::format("{}", s.trigger_time_ms));

  auto io = itk::GDCMImageIO::New();
  io->KeepOriginalUIDOn();
  auto writer = itk::ImageFileWriter<Image>::New();
  writer->SetInput(image);
  writer->SetImageIO(io);
  writer->SetFileName(s.file);
  writer->Update();
}

}  // namespace pcisim::anatomy::testing
