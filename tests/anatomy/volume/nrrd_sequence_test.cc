// 4-D NRRD sequences (issue #14: cine frames as one file): x y z time, x fastest and time slowest,
// the time axis without a space direction. Written and read back bit for bit; files as other
// tools write them (Slicer's `list` kind, RAS space, spacings with NaN for time, detached data);
// and the layouts that would be read as the wrong voxels refused naming the file and the field.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "anatomy/volume/volume_io.h"
#include "realtime/allocation_count.h"

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;

class NrrdSequence : public ::testing::Test {
 protected:
  fs::path dir = fs::path(::testing::TempDir()) / ("pcisim-nrrd-sequence-" + std::to_string(::getpid()));
  void SetUp() override { fs::create_directories(dir); }
  void TearDown() override { fs::remove_all(dir); }

  std::string write(const std::string& name, const std::string& text) {
    const std::string path = (dir / name).string();
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
};

// frame t of a 5 x 4 x 3 grid with an oblique direction (a reader that drops or transposes it fails),
// every voxel different across frames
Volume frame(VoxelType type, int t) {
  Volume v = Volume::make({5, 4, 3}, Eigen::Vector3d(0.7, 0.8, 1.25), Eigen::Vector3d(-10.5, 3.25, 7.0), type);
  const double c = std::cos(0.3), s = std::sin(0.3);
  v.direction << c, -s, 0, s, c, 0, 0, 0, 1;
  for (int64_t n = 0; n < v.voxel_count(); ++n) {
    if (type == VoxelType::kInt16) {
      v.hu_i16[n] = static_cast<int16_t>(n * 37 - 1000 + 3000 * t);
    } else {
      v.hu_f32[n] = static_cast<float>(n) * 1.5f - 900.25f + 0.125f * static_cast<float>(t);
    }
  }
  return v;
}

void expect_same(const Volume& a, const Volume& b, int t) {
  EXPECT_EQ(a.dims, b.dims) << "frame " << t;
  EXPECT_EQ(a.type, b.type) << "frame " << t;
  EXPECT_TRUE(a.spacing_mm.isApprox(b.spacing_mm, 1e-12)) << "frame " << t;
  EXPECT_TRUE(a.origin_mm.isApprox(b.origin_mm, 1e-12)) << "frame " << t;
  EXPECT_TRUE(a.direction.isApprox(b.direction, 1e-12)) << "frame " << t;
  EXPECT_EQ(a.hu_i16, b.hu_i16) << "frame " << t;
  EXPECT_EQ(a.hu_f32, b.hu_f32) << "frame " << t;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// the sequence reader's refusal, or "accepted"
std::string sequence_error(const std::string& path) {
  try {
    read_nrrd_sequence(path);
  } catch (const VolumeIoError& e) {
    return e.what();
  }
  return "accepted";
}

std::string shorts(std::initializer_list<int16_t> v) {
  const std::vector<int16_t> d(v);
  return std::string(reinterpret_cast<const char*>(d.data()), d.size() * sizeof(int16_t));
}

// a 2 x 1 x 1 grid over 3 frames: frame t holds 10 t and 10 t + 1
const std::string kSixShorts = shorts({0, 1, 10, 11, 20, 21});

std::string head4(const std::string& sizes = "2 1 1 3", const std::string& extra = "") {
  return "NRRD0004\ntype: short\ndimension: 4\nsizes: " + sizes + "\nendian: little\nencoding: raw\n" + extra;
}

TEST_F(NrrdSequence, AThreeFrameSequenceRoundTripsBitForBit) {
  for (VoxelType type : {VoxelType::kInt16, VoxelType::kFloat32}) {
    for (bool gzip : {false, true}) {
      if (gzip && !volume_io_has_gzip()) continue;
      const std::vector<Volume> frames = {frame(type, 0), frame(type, 1), frame(type, 2)};
      const std::string path = (dir / "seq.nrrd").string();
      write_nrrd_sequence(frames, path, gzip);
      const std::string text = read_file(path);
      EXPECT_NE(text.find("\ndimension: 4\n"), std::string::npos);
      EXPECT_NE(text.find("\nsizes: 5 4 3 3\n"), std::string::npos);
      EXPECT_NE(text.find(") none\n"), std::string::npos);
      EXPECT_NE(text.find("\nkinds: domain domain domain time\n"), std::string::npos);
      const std::vector<Volume> back = read_nrrd_sequence(path, /*require_spacing=*/true);
      ASSERT_EQ(back.size(), 3u);
      for (int t = 0; t < 3; ++t) expect_same(frames[t], back[t], t);
    }
  }
}

TEST_F(NrrdSequence, FilesAsOtherToolsWriteThemAreRead) {
  // Slicer's sequences: the `list` kind, RAS space; time slowest in the data
  const std::string slicer =
      write("slicer.nrrd", head4("2 1 1 3",
                                 "space: right-anterior-superior\nkinds: domain domain domain list\n"
                                 "space directions: (0.5,0,0) (0,2,0) (0,0,3) none\nspace origin: (10,20,30)\n\n") +
                               kSixShorts);
  const std::vector<Volume> s = read_nrrd_sequence(slicer, true);
  ASSERT_EQ(s.size(), 3u);
  for (int t = 0; t < 3; ++t) {
    EXPECT_EQ(s[t].dims, (std::array<int64_t, 3>{2, 1, 1}));
    EXPECT_EQ(s[t].hu_i16, (std::vector<int16_t>{int16_t(10 * t), int16_t(10 * t + 1)})) << "frame " << t;
    EXPECT_TRUE(s[t].origin_mm.isApprox(Eigen::Vector3d(-10, -20, 30)));
    EXPECT_TRUE(s[t].spacing_mm.isApprox(Eigen::Vector3d(0.5, 2, 3)));
    EXPECT_TRUE(s[t].direction.isApprox(Eigen::Vector3d(-1, -1, 1).asDiagonal().toDenseMatrix()));
  }
  // per-axis spacings, NaN for time (the spec's way), and no kinds
  const std::vector<Volume> sp =
      read_nrrd_sequence(write("spacings.nrrd", head4("2 1 1 3", "spacings: 0.5 2 3 nan\n\n") + kSixShorts), true);
  ASSERT_EQ(sp.size(), 3u);
  EXPECT_TRUE(sp[2].spacing_mm.isApprox(Eigen::Vector3d(0.5, 2, 3)));
  EXPECT_EQ(sp[2].hu_i16[1], 21);
  // detached data, big endian, kind none for the frames
  const std::string be = shorts({0x0100, 0x0200, 0x0300, 0x0400, 0x0500, 0x0600});
  write("voxels.raw", be);
  const std::vector<Volume> d =
      read_nrrd_sequence(write("detached.nhdr",
                               "NRRD0005\ntype: short\ndimension: 4\nsizes: 2 1 1 3\nendian: big\nencoding: raw\n"
                               "kinds: space space space none\ndata file: voxels.raw\n"));
  ASSERT_EQ(d.size(), 3u);
  EXPECT_EQ(d[2].hu_i16, (std::vector<int16_t>{5, 6}));
}

TEST_F(NrrdSequence, LayoutsThatWouldBeMisreadAreRefusedNamingTheField) {
  struct Case {
    const char* file;
    std::string text;
    const char* expect;
  };
  const Case cases[] = {
      {"moving_time.nrrd", head4("2 1 1 3", "space directions: (1,0,0) (0,1,0) (0,0,1) (0,0,0.5)\n\n") + kSixShorts,
       "moving_time.nrrd: space directions: the 4th (time) axis has the direction '(0,0,0.5)': a sequence's time "
       "axis has none (expected 'none' last)"},
      {"none_x.nrrd", head4("2 1 1 3", "space directions: none (0,1,0) (0,0,1) none\n\n") + kSixShorts,
       "none_x.nrrd: space directions: axis 0 is 'none', expected a vector (x,y,z)"},
      {"three_dirs.nrrd", head4("2 1 1 3", "space directions: (1,0,0) (0,1,0) (0,0,1)\n\n") + kSixShorts,
       "three_dirs.nrrd: space directions: expected (x,y,z) (x,y,z) (x,y,z) none, got '(1,0,0) (0,1,0) (0,0,1)'"},
      {"one_frame.nrrd", head4("2 1 1 1", "\n") + shorts({0, 1}),
       "one_frame.nrrd: sizes: the time axis has 1 frame: a sequence needs at least 2 (one volume belongs in a 3-D "
       "file)"},
      {"time_first.nrrd", head4("3 2 1 2", "kinds: time domain domain domain\n\n") + kSixShorts,
       "time_first.nrrd: kinds: axis 0 is 'time' in 'time domain domain domain': a sequence has x, y, z first "
       "(domain or space) and time last"},
      {"vector.nrrd", head4("2 1 1 3", "kinds: domain domain domain 3-vector\n\n") + kSixShorts,
       "vector.nrrd: kinds: axis 3 is '3-vector' in 'domain domain domain 3-vector': expected time, list or none "
       "(the frames)"},
      {"kinds3.nrrd", head4("2 1 1 3", "kinds: domain domain domain\n\n") + kSixShorts,
       "kinds3.nrrd: kinds: expected 4 kinds (x y z time), got 'domain domain domain'"},
      {"sizes3.nrrd", head4("2 1 1", "\n") + kSixShorts,
       "sizes3.nrrd: sizes: expected 4 positive integers (x y z time), got '2 1 1'"},
      {"short.nrrd", head4("2 1 1 3", "\n") + shorts({0, 1, 10, 11, 20}),
       "short.nrrd: sizes: 2x1x1 int16 voxels x 3 frames need 12 bytes but the data (short.nrrd) holds 10"},
      {"five_d.nrrd", "NRRD0004\ntype: short\ndimension: 5\nsizes: 2 1 1 3 1\nencoding: raw\n\n" + kSixShorts,
       "five_d.nrrd: dimension: expected 4 (x y z time), got '5'"},
      {"three_d.nrrd", "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 1 1\nencoding: raw\n\n" + shorts({0, 1}),
       "three_d.nrrd: dimension: expected 4 (x y z time), got '3': a 3-D file holds one volume, not a sequence "
       "(read it with read_nrrd; give a sequence of 3-D files as a folder or one file per frame)"},
  };
  for (const Case& c : cases) EXPECT_EQ(sequence_error(write(c.file, c.text)), c.expect) << c.file;
}

TEST_F(NrrdSequence, TheThreeDReaderRefusesASequencePointingAtTheSequenceReader) {
  const std::string path = write("cine.nrrd", head4("2 1 1 3", "\n") + kSixShorts);
  const std::string want =
      "cine.nrrd: dimension: expected 3, got '4': a 4-D file holds a sequence of volumes (x y z time); read it with "
      "read_nrrd_sequence (pcisim-model motion --sequence FILE)";
  for (auto* read :
       {+[](const std::string& p) { return read_nrrd(p); }, +[](const std::string& p) { return read_volume(p); }}) {
    try {
      read(path);
      ADD_FAILURE() << "accepted";
    } catch (const VolumeIoError& e) {
      EXPECT_EQ(std::string(e.what()), want);
    }
  }
}

TEST_F(NrrdSequence, HostileSizesAndVoxelsAreRefusedBeforeAllocatingTheirClaim) {
  // each axis fine, the product over the limit (and over int64 for the first)
  for (const char* sizes : {"4294967296 4294967296 2 4294967296", "1024 1024 512 3"}) {
    const std::string path = write("big.nrrd", head4(sizes, "\n") + kSixShorts);
    pcisim::realtime::AllocationCount alloc;
    const std::string m = sequence_error(path);
    EXPECT_LT(alloc.largest(), 1 << 20) << sizes;
    EXPECT_EQ(m.rfind("big.nrrd: sizes: ", 0), 0u) << m;
    EXPECT_NE(m.find("frames: over the 1073741824 voxel limit"), std::string::npos) << m;
  }
  // a NaN in frame 1: named in the stacked block, with the way back to the frame
  float voxels[6] = {0, 1, 2, std::nanf(""), 4, 5};
  const std::string m =
      sequence_error(write("nan.nrrd", "NRRD0004\ntype: float\ndimension: 4\nsizes: 2 1 1 3\nencoding: raw\n\n" +
                                           std::string(reinterpret_cast<const char*>(voxels), sizeof voxels)));
  EXPECT_EQ(m,
            "nan.nrrd: voxels: voxel (1, 0, 1) is nan: every voxel must be a finite HU value (the 3 frames of 2x1x1 "
            "read as one 2x1x3 block: frame = k / 1)");
}

TEST_F(NrrdSequence, TheWriterRefusesFramesOnDifferentGrids) {
  const std::string path = (dir / "w.nrrd").string();
  auto message = [&](const std::vector<Volume>& frames) {
    try {
      write_nrrd_sequence(frames, path);
    } catch (const VolumeIoError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const Volume f0 = frame(VoxelType::kInt16, 0);
  Volume shifted = frame(VoxelType::kInt16, 1);
  shifted.origin_mm.x() += 0.5;
  Volume smaller = Volume::make({5, 4, 2}, f0.spacing_mm, f0.origin_mm, f0.type);
  smaller.direction = f0.direction;
  Volume broken = f0;
  broken.hu_i16.pop_back();
  EXPECT_EQ(message({f0}), "w.nrrd: frames: a sequence needs at least 2, got 1");
  EXPECT_EQ(message({f0, f0, shifted}), "w.nrrd: frame 2: origin differs from frame 0's (a sequence has one grid)");
  EXPECT_EQ(message({f0, smaller}), "w.nrrd: frame 1: dims 5x4x2 differ from frame 0's (a sequence has one grid)");
  EXPECT_EQ(message({f0, frame(VoxelType::kFloat32, 1)}),
            "w.nrrd: frame 1: voxel type differs from frame 0's (a sequence has one grid)");
  EXPECT_NE(message({f0, broken}).find("w.nrrd: frame 1: 59 voxels of data"), std::string::npos);
  EXPECT_FALSE(fs::exists(path));
}

}  // namespace
}  // namespace pcisim::anatomy
