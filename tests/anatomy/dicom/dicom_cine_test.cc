// A DICOM cine (issue #14: "Frames as ... DICOM"): one series of 3 temporal positions x 8 slices of
// 16 x 16 pixels, a block moving one voxel a frame, reads as 3 volumes in time order with their
// voxels and geometry, whatever the files' names and instance numbers; grouped by Temporal
// Position Identifier, else by Trigger Time. A time point missing a slice or with moved slices, a
// single time point and an image without the time key are refused naming what is wrong.
#include <gtest/gtest.h>

#include <unistd.h>

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <filesystem>
#include <numeric>
#include <random>

#include "anatomy/dicom/dicom_series.h"
#include "tests/anatomy/dicom/dicom_writer.h"

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;

constexpr const char* kCineSeries = "1.2.826.0.1.3680043.2.1125.3.1";
constexpr int kFrames = 3;

// frame t: 16 x 16 x 8 voxels, 0.7 x 0.9 mm pixels, 1.5 mm slices, rows rotated 15 deg about z;
// a textured background and a 4 x 4 x 3 block of 900 HU whose x index starts at 5 + t
Volume cine_frame(int t) {
  Volume v =
      Volume::make({16, 16, 8}, Eigen::Vector3d(0.7, 0.9, 1.5), Eigen::Vector3d(-20.5, 14.25, 60.0), VoxelType::kInt16);
  v.direction = Eigen::AngleAxisd(15 * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (int64_t k = 0; k < 8; ++k)
    for (int64_t j = 0; j < 16; ++j)
      for (int64_t i = 0; i < 16; ++i) {
        const bool block = i >= 5 + t && i < 9 + t && j >= 6 && j < 10 && k >= 2 && k < 5;
        v.hu_i16[v.linear_index(i, j, k)] = static_cast<int16_t>(block ? 900 : -200 + (i * 7 + j * 3 + k * 11) % 50);
      }
  return v;
}

struct CineOptions {
  bool temporal_position = true, trigger_time = true;
  bool shuffled = false;  // file names and instance numbers in a random order, not time order
  int frames = kFrames;
  int moved_frame = -1;     // this frame's slices shifted 2 mm along the rows
  int untagged_image = -1;  // this image (t * 8 + k) without Temporal Position Identifier
};

// one file per image; by default img_<t>_<k>.dcm with instance numbers in time then slice order
void write_cine(const fs::path& dir, const CineOptions& o = {}) {
  fs::create_directories(dir);
  const int slices = 8;
  std::vector<int> order(o.frames * slices);
  std::iota(order.begin(), order.end(), 0);
  if (o.shuffled) std::shuffle(order.begin(), order.end(), std::mt19937(7));
  for (int t = 0; t < o.frames; ++t) {
    const Volume v = cine_frame(t);
    for (int k = 0; k < slices; ++k) {
      const int n = order[t * slices + k];  // the image's place in names and instance numbers
      testing::DicomSlice s;
      s.file = (dir / (o.shuffled ? fmt::format("img_{:03d}.dcm", n) : fmt::format("img_{}_{}.dcm", t, k))).string();
      s.series_uid = kCineSeries;
      s.study_uid = "1.2.826.0.1.3680043.2.1125.1";
      s.instance = n + 1;
      const Eigen::Vector3d p = v.index_to_physical_mm(Eigen::Vector3d(0, 0, double(k))) +
                                v.direction.col(0) * (t == o.moved_frame ? 2.0 : 0.0);
      s.position_mm = {p.x(), p.y(), p.z()};
      for (int a = 0; a < 3; ++a) {
        s.orientation[a] = v.direction(a, 0);
        s.orientation[3 + a] = v.direction(a, 1);
      }
      s.pixel_spacing_mm = {v.spacing_mm.y(), v.spacing_mm.x()};  // between rows, between columns
      s.slice_thickness_mm = v.spacing_mm.z();
      if (o.temporal_position && t * slices + k != o.untagged_image) s.temporal_position = t + 1;
      if (o.trigger_time) s.trigger_time_ms = 40.0 * t;
      const int64_t plane = v.dims[0] * v.dims[1];
      std::vector<int16_t> hu(v.hu_i16.begin() + k * plane, v.hu_i16.begin() + (k + 1) * plane);
      testing::write_dicom_slice(s, int(v.dims[0]), int(v.dims[1]), hu);
    }
  }
}

class DicomCine : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pcisim-dicom-cine-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string refusal() const {
    try {
      read_dicom_cine(dir_.string());
    } catch (const DicomError& e) {
      return e.what();
    }
    return "";
  }
  // every frame's voxels and geometry as written, in time order
  static void expect_the_written_frames(const std::vector<Volume>& frames) {
    ASSERT_EQ(frames.size(), size_t(kFrames));
    for (int t = 0; t < kFrames; ++t) {
      const Volume want = cine_frame(t);
      const Volume& got = frames[t];
      ASSERT_EQ(got.dims, want.dims) << "frame " << t;
      EXPECT_LT((got.origin_mm - want.origin_mm).norm(), 1e-6) << "frame " << t << ": " << got.origin_mm.transpose();
      EXPECT_LT((got.spacing_mm - want.spacing_mm).norm(), 1e-6) << "frame " << t << ": " << got.spacing_mm.transpose();
      EXPECT_LT((got.direction - want.direction).norm(), 1e-6) << "frame " << t << ":\n" << got.direction;
      ASSERT_EQ(got.type, VoxelType::kInt16) << "frame " << t;
      EXPECT_EQ(got.hu_i16, want.hu_i16) << "frame " << t;
      // the block's first column moved one voxel a frame
      EXPECT_EQ(got.hu(4 + t, 7, 3), want.hu(4 + t, 7, 3)) << "frame " << t;
      EXPECT_NE(got.hu(4 + t, 7, 3), 900) << "frame " << t;
      EXPECT_EQ(got.hu(5 + t, 7, 3), 900) << "frame " << t;
    }
  }
  fs::path dir_;
};

TEST_F(DicomCine, ThreeTimePointsReadAsThreeFramesInTimeOrder) {
  write_cine(dir_);
  expect_the_written_frames(read_dicom_cine(dir_.string()));
  // the series' UID named gives the same
  expect_the_written_frames(read_dicom_cine(dir_.string(), kCineSeries));
}

// file names and instance numbers in a random order: the temporal position orders the frames
TEST_F(DicomCine, AShuffledFileOrderStillGivesTimeOrder) {
  CineOptions o;
  o.shuffled = true;
  write_cine(dir_, o);
  expect_the_written_frames(read_dicom_cine(dir_.string()));
}

// without Temporal Position Identifier the Trigger Time groups and orders the images
TEST_F(DicomCine, TriggerTimeGroupsTheImagesWithoutATemporalPosition) {
  CineOptions o;
  o.temporal_position = false;
  o.shuffled = true;
  write_cine(dir_, o);
  expect_the_written_frames(read_dicom_cine(dir_.string()));
  fs::remove(dir_ / "img_004.dcm");
  const std::string why = refusal();
  EXPECT_NE(why.find(dir_.string() + ": trigger time "), std::string::npos) << why;
  EXPECT_NE(why.find(": 7 slices, trigger time "), std::string::npos) << why;
}

TEST_F(DicomCine, ATimePointMissingASliceIsRefusedNamingIt) {
  write_cine(dir_);
  fs::remove(dir_ / "img_1_3.dcm");  // temporal position 2's fourth slice
  const std::string why = refusal();
  EXPECT_NE(why.find(dir_.string() + ": temporal position 2: 7 slices, temporal position 1 has 8 (a missing or "
                                     "extra slice)"),
            std::string::npos)
      << why;
}

TEST_F(DicomCine, ATimePointWhoseSlicesMovedIsRefusedNamingIt) {
  CineOptions o;
  o.moved_frame = 2;
  write_cine(dir_, o);
  const std::string why = refusal();
  EXPECT_NE(why.find(dir_.string() + ": temporal position 3: ImagePositionPatient of its first slice (img_2_0.dcm)"),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("temporal position 1's (img_0_0.dcm)"), std::string::npos) << why;
}

TEST_F(DicomCine, ASingleTimePointIsRefused) {
  CineOptions o;
  o.frames = 1;
  write_cine(dir_, o);
  std::string why = refusal();
  EXPECT_NE(why.find(dir_.string() + ": one time point: a 3-D series, not a cine"), std::string::npos) << why;
  // and so is a series without any time tag
  fs::remove_all(dir_);
  o.temporal_position = o.trigger_time = false;
  write_cine(dir_, o);
  why = refusal();
  EXPECT_NE(why.find(dir_.string() + ": one time point: a 3-D series, not a cine"), std::string::npos) << why;
  // read_dicom_series reads it
  EXPECT_EQ(read_dicom_series(dir_.string()).hu_i16, cine_frame(0).hu_i16);
}

TEST_F(DicomCine, AnImageWithoutTheTimeKeyIsRefusedNamingIt) {
  CineOptions o;
  o.untagged_image = 8 + 5;  // temporal position 2's sixth slice
  write_cine(dir_, o);
  const std::string why = refusal();
  EXPECT_NE(why.find("img_1_5.dcm: no Temporal Position Identifier (0020,0100), which other files of the series give"),
            std::string::npos)
      << why;
}

}  // namespace
}  // namespace pcisim::anatomy
