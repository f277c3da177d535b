#include "anatomy/volume/volume_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>
#include <string>

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir() {
  const fs::path d = fs::temp_directory_path() / ("pcisim_xray_io_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

Volume sample_volume(VoxelType type) {
  Volume v = Volume::make({5, 4, 3}, Eigen::Vector3d(0.7, 0.8, 1.25), Eigen::Vector3d(-10.5, 3.25, 7.0), type);
  // an oblique direction, so a reader that drops or transposes it fails
  const double c = std::cos(0.3), s = std::sin(0.3);
  v.direction << c, -s, 0, s, c, 0, 0, 0, 1;
  for (int64_t n = 0; n < v.voxel_count(); ++n) {
    if (type == VoxelType::kInt16) {
      v.hu_i16[n] = static_cast<int16_t>(n * 37 - 1000);
    } else {
      v.hu_f32[n] = static_cast<float>(n) * 1.5f - 900.25f;
    }
  }
  return v;
}

void expect_same(const Volume& a, const Volume& b) {
  EXPECT_EQ(a.dims, b.dims);
  EXPECT_EQ(a.type, b.type);
  EXPECT_TRUE(a.spacing_mm.isApprox(b.spacing_mm, 1e-12));
  EXPECT_TRUE(a.origin_mm.isApprox(b.origin_mm, 1e-12));
  EXPECT_TRUE(a.direction.isApprox(b.direction, 1e-12));
  EXPECT_EQ(a.hu_i16, b.hu_i16);
  EXPECT_EQ(a.hu_f32, b.hu_f32);
}

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

// the message thrown when reading path, or "" when it reads fine
std::string read_error(const fs::path& p) {
  try {
    read_volume(p.string());
  } catch (const VolumeIoError& e) {
    return e.what();
  }
  return "";
}

TEST(VolumeIo, MetaImageInlineRoundTrip) {
  for (VoxelType t : {VoxelType::kInt16, VoxelType::kFloat32}) {
    const Volume v = sample_volume(t);
    const fs::path p = temp_dir() / "a.mha";
    write_metaimage(v, p.string());
    expect_same(v, read_volume(p.string()));
  }
}

TEST(VolumeIo, MetaImageDetachedRoundTrip) {
  const Volume v = sample_volume(VoxelType::kInt16);
  const fs::path p = temp_dir() / "b.mhd";
  write_metaimage(v, p.string());
  EXPECT_TRUE(fs::exists(temp_dir() / "b.raw"));
  EXPECT_EQ(fs::file_size(temp_dir() / "b.raw"), static_cast<uintmax_t>(v.data_bytes()));
  expect_same(v, read_volume(p.string()));
}

TEST(VolumeIo, NrrdRawRoundTrip) {
  for (VoxelType t : {VoxelType::kInt16, VoxelType::kFloat32}) {
    const Volume v = sample_volume(t);
    const fs::path p = temp_dir() / "c.nrrd";
    write_nrrd(v, p.string());
    expect_same(v, read_volume(p.string()));
  }
}

TEST(VolumeIo, NrrdGzipRoundTripOrClearRejection) {
  const Volume v = sample_volume(VoxelType::kInt16);
  const fs::path p = temp_dir() / "d.nrrd";
  if (volume_io_has_gzip()) {
    write_nrrd(v, p.string(), /*gzip=*/true);
    expect_same(v, read_volume(p.string()));
  } else {
    try {
      write_nrrd(v, p.string(), true);
      FAIL() << "gzip write without zlib must throw";
    } catch (const VolumeIoError& e) {
      EXPECT_NE(std::string(e.what()).find("zlib"), std::string::npos) << e.what();
    }
  }
}

TEST(VolumeIo, NrrdRasSpaceIsConvertedToLps) {
  const fs::path p = temp_dir() / "ras.nrrd";
  std::string text =
      "NRRD0004\ntype: short\ndimension: 3\nspace: right-anterior-superior\nsizes: 2 1 1\n"
      "space directions: (0.5,0,0) (0,2,0) (0,0,3)\nendian: little\nencoding: raw\n"
      "space origin: (10,20,30)\n\n";
  const int16_t data[2] = {7, -8};
  text.append(reinterpret_cast<const char*>(data), sizeof(data));
  write_text(p, text);
  const Volume v = read_volume(p.string());
  EXPECT_TRUE(v.origin_mm.isApprox(Eigen::Vector3d(-10, -20, 30)));
  EXPECT_TRUE(v.spacing_mm.isApprox(Eigen::Vector3d(0.5, 2, 3)));
  EXPECT_TRUE(v.direction.isApprox(Eigen::Vector3d(-1, -1, 1).asDiagonal().toDenseMatrix()));
  EXPECT_EQ(v.hu_i16[1], -8);
}

TEST(VolumeIo, MetaImageBigEndianIsSwapped) {
  const fs::path p = temp_dir() / "msb.mha";
  std::string text =
      "ObjectType = Image\nNDims = 3\nBinaryDataByteOrderMSB = True\nDimSize = 1 1 1\n"
      "ElementType = MET_SHORT\nElementDataFile = LOCAL\n";
  text += std::string("\x01\x02", 2);
  write_text(p, text);
  EXPECT_EQ(read_volume(p.string()).hu_i16[0], 0x0102);
}

struct BadCase {
  const char* file;
  std::string text;
  const char* expect;  // text the message must contain (after "<file>: ")
};

TEST(VolumeIo, BadFilesAreRejectedNamingFileAndField) {
  const std::string ok_mha_head = "ObjectType = Image\nNDims = 3\nElementSpacing = 1 1 1\n";
  const std::string two_shorts("\0\0\0\0", 4);
  const std::string nrrd_head = "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 1 1\nendian: little\n";
  const BadCase cases[] = {
      {"ndims.mha", "NDims = 2\nDimSize = 2 1\nElementType = MET_SHORT\nElementDataFile = LOCAL\n" + two_shorts,
       "ndims.mha: NDims: expected 3, got '2'"},
      {"dims.mha", ok_mha_head + "DimSize = 2 1\nElementType = MET_SHORT\nElementDataFile = LOCAL\n" + two_shorts,
       "dims.mha: DimSize: expected 3 positive integers, got '2 1'"},
      {"negdims.mha", ok_mha_head + "DimSize = 2 -1 1\nElementType = MET_SHORT\nElementDataFile = LOCAL\n",
       "negdims.mha: DimSize: expected 3 positive integers, got '2 -1 1'"},
      {"type.mha", ok_mha_head + "DimSize = 2 1 1\nElementType = MET_UCHAR\nElementDataFile = LOCAL\nab",
       "type.mha: ElementType: unsupported 'MET_UCHAR' (expected MET_SHORT or MET_FLOAT)"},
      {"short.mha",
       ok_mha_head + "DimSize = 2 1 1\nElementType = MET_SHORT\nElementDataFile = LOCAL\n" + std::string("\0\0\0", 3),
       "short.mha: DimSize: 2x1x1 int16 voxels need 4 bytes but the data (short.mha) holds 3"},
      {"long.mha",
       ok_mha_head + "DimSize = 2 1 1\nElementType = MET_SHORT\nElementDataFile = LOCAL\n" + two_shorts + "x",
       "long.mha: DimSize: 2x1x1 int16 voxels need 4 bytes but the data (long.mha) holds 5"},
      {"nodata.mha", ok_mha_head + "DimSize = 2 1 1\nElementType = MET_SHORT\n",
       "nodata.mha: ElementDataFile: missing (it must be the last key)"},
      {"notype.mha", ok_mha_head + "DimSize = 2 1 1\nElementDataFile = LOCAL\n" + two_shorts,
       "notype.mha: ElementType: missing"},
      {"spacing.mha",
       "NDims = 3\nElementSpacing = 1 0 1\nDimSize = 2 1 1\nElementType = MET_SHORT\nElementDataFile = LOCAL\n" +
           two_shorts,
       "spacing.mha: ElementSpacing: expected 3 positive numbers, got '1 0 1'"},
      {"offset.mha",
       "NDims = 3\nOffset = 1 x 1\nDimSize = 2 1 1\nElementType = MET_SHORT\nElementDataFile = LOCAL\n" + two_shorts,
       "offset.mha: Offset: expected 3 numbers, got '1 x 1'"},
      {"matrix.mha",
       "NDims = 3\nTransformMatrix = 1 0 0 1 0 0 0 0 1\nDimSize = 2 1 1\nElementType = MET_SHORT\nElementDataFile = "
       "LOCAL\n" +
           two_shorts,
       "matrix.mha: TransformMatrix: the direction matrix is singular"},
      {"garbage.mha", "NDims = 3\nthis line has no equals sign\n",
       "garbage.mha: header: line 'this line has no equals sign' is not 'Key = Value'"},
      {"missing.mhd", "NDims = 3\nDimSize = 2 1 1\nElementType = MET_SHORT\nElementDataFile = nowhere.raw\n",
       "missing.mhd: ElementDataFile: cannot open"},
      {"magic.nrrd", "NRRX0004\n", "magic.nrrd: magic: the file does not start with NRRD0001..NRRD0005"},
      {"dim.nrrd", "NRRD0004\ntype: short\ndimension: 2\nsizes: 2 1\nencoding: raw\n\n" + two_shorts,
       "dim.nrrd: dimension: expected 3, got '2'"},
      {"ntype.nrrd", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 1 1\nencoding: raw\n\nab",
       "ntype.nrrd: type: unsupported 'uchar' (expected short or float)"},
      {"enc.nrrd", nrrd_head + "encoding: ascii\n\n1 2",
       "enc.nrrd: encoding: unsupported 'ascii' (expected raw or gzip)"},
      {"nsize.nrrd", nrrd_head + "encoding: raw\n\n" + std::string("\0\0", 2),
       "nsize.nrrd: sizes: 2x1x1 int16 voxels need 4 bytes but the data (nsize.nrrd) holds 2"},
      {"nosizes.nrrd", "NRRD0004\ntype: short\ndimension: 3\nencoding: raw\n\n", "nosizes.nrrd: sizes: missing"},
      {"dirs.nrrd",
       nrrd_head + "space: left-posterior-superior\nspace directions: (1,0,0) none (0,0,1)\nencoding: raw\n\n" +
           two_shorts,
       "dirs.nrrd: space directions: expected three vectors (x,y,z), got '(1,0,0) none (0,0,1)'"},
      {"space.nrrd", nrrd_head + "space: scanner-xyz\nencoding: raw\n\n" + two_shorts,
       "space.nrrd: space: unsupported 'scanner-xyz'"},
      {"endian.nrrd",
       "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 1 1\nendian: middle\nencoding: raw\n\n" + two_shorts,
       "endian.nrrd: endian: expected little or big, got 'middle'"},
      {"line.nrrd", nrrd_head + "encoding: raw\nthis is not a field\n\n",
       "line.nrrd: header: line 'this is not a field' is not 'field: value'"},
      {"volume.xyz", "whatever", "volume.xyz: file name: expected .mha, .mhd, .nrrd or .nhdr"},
  };
  for (const BadCase& c : cases) {
    const fs::path p = temp_dir() / c.file;
    write_text(p, c.text);
    const std::string msg = read_error(p);
    EXPECT_NE(msg.find(c.expect), std::string::npos) << c.file << ": got '" << msg << "'";
  }
}

TEST(VolumeIo, GzipNrrdWithCorruptDataIsRejected) {
  const fs::path p = temp_dir() / "gz.nrrd";
  write_text(p, "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 1 1\nendian: little\nencoding: gzip\n\nnot gzip at all");
  const std::string msg = read_error(p);
  if (volume_io_has_gzip()) {
    EXPECT_NE(msg.find("gz.nrrd: encoding: gzip: corrupt or truncated compressed data"), std::string::npos) << msg;
  } else {
    EXPECT_NE(msg.find("gz.nrrd: encoding: gzip needs zlib"), std::string::npos) << msg;
  }
}

TEST(VolumeIo, MissingFileNamesThePath) {
  const std::string msg = read_error(temp_dir() / "absent.mha");
  EXPECT_NE(msg.find("absent.mha: cannot open the file: No such file or directory"), std::string::npos) << msg;
}

TEST(Volume, IndexAndPhysicalRoundTrip) {
  const Volume v = sample_volume(VoxelType::kFloat32);
  const Eigen::Vector3d ijk(1.25, 2.5, -0.75);
  EXPECT_TRUE(v.physical_to_index(v.index_to_physical_mm(ijk)).isApprox(ijk, 1e-12));
  EXPECT_TRUE(v.index_to_physical_mm(Eigen::Vector3d::Zero()).isApprox(v.origin_mm));
  EXPECT_EQ(validate(v), "");
  Volume bad = v;
  bad.hu_f32.pop_back();
  EXPECT_NE(validate(bad).find("59 voxels of data for dims 5x4x3"), std::string::npos) << validate(bad);
}

}  // namespace
}  // namespace pcisim::anatomy
