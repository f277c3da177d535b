// A DICOM CT series reads to the same voxels and geometry as the same volume in NRRD (oblique
// orientation, non-square pixels, rescaled HU); a missing slice, uneven spacing, an empty or
// missing folder and an ambiguous folder are refused naming what is wrong.
#include <gtest/gtest.h>

#include <unistd.h>

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <filesystem>

#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "anatomy/case/case_folder.h"
#include "anatomy/dicom/dicom_series.h"
#include "anatomy/phantom/phantom_case.h"
#include "anatomy/volume/volume_io.h"
#include "tests/anatomy/dicom/dicom_writer.h"

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;

// 12 x 10 x 8 voxels, rows rotated 20 deg about z and tilted 10 deg about x, 0.6 x 0.8 mm pixels,
// 1.25 mm slices, HU from -1000 to +1500
Volume oblique_volume() {
  Volume v = Volume::make({12, 10, 8}, Eigen::Vector3d(0.6, 0.8, 1.25), Eigen::Vector3d(-31.5, 12.25, 104.0),
                          VoxelType::kInt16);
  v.direction = (Eigen::AngleAxisd(20 * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                 Eigen::AngleAxisd(10 * M_PI / 180, Eigen::Vector3d::UnitX()))
                    .toRotationMatrix();
  for (int64_t n = 0; n < v.voxel_count(); ++n) v.hu_i16[n] = static_cast<int16_t>(-1000 + (n * 37) % 2501);
  return v;
}

// one file per slice, slice_000.dcm ...; `shift_mm` moves one slice along the normal
void write_series(const Volume& v, const fs::path& dir, const std::string& series_uid, int shifted_slice = -1,
                  double shift_mm = 0.0) {
  fs::create_directories(dir);
  for (int64_t k = 0; k < v.dims[2]; ++k) {
    testing::DicomSlice s;
    s.file = (dir / fmt::format("{}_slice_{:03d}.dcm", series_uid.substr(series_uid.size() - 1), k)).string();
    s.series_uid = series_uid;
    s.study_uid = "1.2.826.0.1.3680043.2.1125.1";
    s.instance = static_cast<int>(k + 1);
    const Eigen::Vector3d p = v.index_to_physical_mm(Eigen::Vector3d(0, 0, double(k))) +
                              v.direction.col(2) * (k == shifted_slice ? shift_mm : 0.0);
    s.position_mm = {p.x(), p.y(), p.z()};
    for (int a = 0; a < 3; ++a) {
      s.orientation[a] = v.direction(a, 0);
      s.orientation[3 + a] = v.direction(a, 1);
    }
    s.pixel_spacing_mm = {v.spacing_mm.y(), v.spacing_mm.x()};  // between rows, between columns
    s.slice_thickness_mm = v.spacing_mm.z();
    const int64_t plane = v.dims[0] * v.dims[1];
    std::vector<int16_t> hu(v.hu_i16.begin() + k * plane, v.hu_i16.begin() + (k + 1) * plane);
    testing::write_dicom_slice(s, int(v.dims[0]), int(v.dims[1]), hu);
  }
}

constexpr const char* kSeriesA = "1.2.826.0.1.3680043.2.1125.2.1";
constexpr const char* kSeriesB = "1.2.826.0.1.3680043.2.1125.2.2";

class DicomSeries : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pcisim-dicom-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string refusal(const std::string& uid = "") const {
    try {
      read_dicom_series(dir_.string(), uid);
    } catch (const DicomError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(DicomSeries, SameVoxelsAndGeometryAsTheSameVolumeInNrrd) {
  const Volume v = oblique_volume();
  write_series(v, dir_, kSeriesA);
  write_nrrd(v, (dir_.parent_path() / (dir_.filename().string() + ".nrrd")).string());
  const Volume nrrd = read_nrrd((dir_.parent_path() / (dir_.filename().string() + ".nrrd")).string());
  fs::remove(dir_.parent_path() / (dir_.filename().string() + ".nrrd"));
  const Volume dcm = read_dicom_series(dir_.string());
  ASSERT_EQ(dcm.dims, nrrd.dims);
  EXPECT_LT((dcm.origin_mm - nrrd.origin_mm).norm(), 1e-6) << dcm.origin_mm.transpose();
  EXPECT_LT((dcm.spacing_mm - nrrd.spacing_mm).norm(), 1e-6) << dcm.spacing_mm.transpose();
  EXPECT_LT((dcm.direction - nrrd.direction).norm(), 1e-6) << dcm.direction;
  ASSERT_EQ(dcm.type, VoxelType::kInt16);
  EXPECT_EQ(dcm.hu_i16, nrrd.hu_i16);
  // a point maps to the same voxel in both
  const Eigen::Vector3d p = nrrd.index_to_physical_mm(Eigen::Vector3d(7, 3, 5));
  EXPECT_LT((dcm.physical_to_index(p) - Eigen::Vector3d(7, 3, 5)).norm(), 1e-6);
}

TEST_F(DicomSeries, AMissingSliceIsRefusedNamingTheSliceAfterTheGap) {
  write_series(oblique_volume(), dir_, kSeriesA);
  fs::remove(dir_ / "1_slice_004.dcm");
  const std::string why = refusal();
  EXPECT_NE(why.find("1_slice_005.dcm: gap of 2.50 mm after the previous slice (1_slice_003.dcm), the series' "
                     "spacing is 1.25 mm (a missing slice or uneven spacing)"),
            std::string::npos)
      << why;
}

TEST_F(DicomSeries, UnevenSpacingIsRefusedNamingTheSlice) {
  write_series(oblique_volume(), dir_, kSeriesA, /*shifted_slice=*/5, /*shift_mm=*/0.4);
  const std::string why = refusal();
  EXPECT_NE(why.find("1_slice_005.dcm: gap of 1.65 mm after the previous slice (1_slice_004.dcm)"), std::string::npos)
      << why;
}

TEST_F(DicomSeries, AnEmptyOrMissingFolderIsRefused) {
  EXPECT_NE(refusal().find(dir_.string() + ": not a folder"), std::string::npos) << refusal();
  fs::create_directories(dir_);
  EXPECT_NE(refusal().find(dir_.string() + ": no DICOM series found"), std::string::npos) << refusal();
}

TEST_F(DicomSeries, TwoSeriesNeedAUid) {
  Volume small = oblique_volume();
  write_series(small, dir_, kSeriesA);
  Volume other = Volume::make({6, 5, 3}, Eigen::Vector3d(1, 1, 2), Eigen::Vector3d::Zero(), VoxelType::kInt16);
  for (auto& h : other.hu_i16) h = 40;
  write_series(other, dir_, kSeriesB);
  const std::string why = refusal();
  EXPECT_NE(why.find("2 series found"), std::string::npos) << why;
  EXPECT_NE(why.find(kSeriesA), std::string::npos) << why;
  EXPECT_NE(why.find(kSeriesB), std::string::npos) << why;
  const Volume b = read_dicom_series(dir_.string(), kSeriesB);
  EXPECT_EQ(b.dims, other.dims);
  EXPECT_EQ(b.hu_i16, other.hu_i16);
  EXPECT_NE(refusal("1.2.3").find("no series 1.2.3"), std::string::npos) << refusal("1.2.3");
}

// sets a US tag (group 0x0028) in a written DICOM file to `value`, in place (explicit or implicit
// VR little endian, as ITK writes it); the pixel data stays as it was
void patch_us_tag(const fs::path& file, uint16_t element, uint16_t value) {
  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const std::string tag{'\x28', '\x00', char(element & 0xff), char(element >> 8)};
  const std::string explicit_vr = tag + std::string("US\x02\x00", 4), implicit_vr = tag + std::string("\x02\0\0\0", 4);
  size_t at = bytes.find(explicit_vr);
  if (at == std::string::npos) at = bytes.find(implicit_vr);
  ASSERT_NE(at, std::string::npos) << file << ": no (0028," << std::hex << element << ") tag";
  bytes[at + 8] = char(value & 0xff);
  bytes[at + 9] = char(value >> 8);
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

// headers claiming 65535 x 65535 pixels a slice are refused from the headers alone, naming the
// numbers and the volume readers' cap, before ITK allocates the series (34 G voxels: 137 GB)
TEST_F(DicomSeries, ASeriesOverTheVoxelCapIsRefusedBeforeAnyVoxelIsRead) {
  write_series(oblique_volume(), dir_, kSeriesA);
  for (const auto& f : fs::directory_iterator(dir_)) {
    patch_us_tag(f.path(), 0x0010, 65535);  // Rows
    patch_us_tag(f.path(), 0x0011, 65535);  // Columns
  }
  // since the header walk (#38) a file's pixel data must hold what Rows x Columns promise, so the
  // walk refuses the 8 GB slice before the series' voxel cap is reached (that cap stays behind it:
  // 65 536 files of 128 x 128 would reach it, too many to write here)
  const std::string why = refusal();
  EXPECT_NE(why.find("PixelData (7FE0,0010): 240 bytes, Rows x Columns x NumberOfFrames x BitsAllocated/8 is "
                     "65535 x 65535 x 1 x 16/8 = 8589672450"),
            std::string::npos)
      << why;
}

// slices of different sizes are refused naming the file
TEST_F(DicomSeries, SlicesOfDifferentSizesAreRefused) {
  write_series(oblique_volume(), dir_, kSeriesA);
  // slice 3 of the same series with 11 rows (10 in the others), its pixel data whole
  Volume taller = oblique_volume();
  taller.dims[1] = 11;
  taller.hu_i16.assign(static_cast<size_t>(taller.voxel_count()), int16_t{-1000});
  write_series(taller, dir_ / "taller", kSeriesA);
  fs::copy_file(dir_ / "taller" / "1_slice_003.dcm", dir_ / "1_slice_003.dcm", fs::copy_options::overwrite_existing);
  fs::remove_all(dir_ / "taller");
  const std::string why = refusal();
  EXPECT_NE(why.find("1_slice_003.dcm: 11 rows x 12 columns, "), std::string::npos) << why;
}

// a case whose CT is a DICOM series folder reads the same CT as the case's NRRD
TEST_F(DicomSeries, ACaseMayNameItsCtAsADicomFolder) {
  PhantomCaseSpec spec;
  spec.ct_dims = {48, 48, 36};
  spec.ct_spacing_mm = 5.0;
  const Case c = make_phantom_case(spec);
  write_case(c, dir_.string());
  write_series(*c.ct, dir_ / "ct_dicom", kSeriesA);
  nlohmann::json j = nlohmann::json::parse(std::ifstream(dir_ / "case.json"));
  j["ct"] = {{"dicom", "ct_dicom"}, {"lumen_enhanced", false}};
  std::ofstream(dir_ / "case.json") << j.dump(1);
  const Case back = read_case(dir_.string(), [](const std::string& f) { return read_dicom_series(f); });
  ASSERT_TRUE(back.ct.has_value());
  EXPECT_EQ(back.ct->dims, c.ct->dims);
  EXPECT_EQ(back.ct->hu_i16, c.ct->hu_i16);
  EXPECT_LT((back.ct->origin_mm - c.ct->origin_mm).norm(), 1e-4);
  // without a DICOM reader the case is refused saying why
  try {
    read_case(dir_.string());
    ADD_FAILURE() << "read a DICOM case without a DICOM reader";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("ct.dicom: this program was built without the DICOM reader"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace pcisim::anatomy
