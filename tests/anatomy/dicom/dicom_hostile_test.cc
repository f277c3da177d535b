// Hostile DICOM series (issue #38): a good 4-slice series written through ITK, then one file of it
// corrupted the way a hostile or broken export would be. Each is refused by read_dicom_series with
// DicomError "<file>: <tag name (gggg,eeee)>: <what>", quickly, before GDCM or ITK sees the file
// (before the check, GDCM asserted on several of these: SIGABRT, gdcmReader.cxx:385,
// gdcmFileMetaInformation.cxx:591, vnl_matrix.hxx). Stray files that are not DICOM are skipped.
#include <gtest/gtest.h>

#include <unistd.h>

#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>

#include "tests/common/file_text.h"
#include "anatomy/dicom/dicom_limits.h"
#include "anatomy/dicom/dicom_precheck.h"
#include "anatomy/dicom/dicom_series.h"
#include "anatomy/dicom/itk_dicom_io.h"
#include "tests/anatomy/dicom/dicom_writer.h"

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;

constexpr const char* kSeries = "1.2.826.0.1.3680043.2.1125.4.1";
constexpr int kColumns = 6, kRows = 5, kSlices = 4;

void put(const fs::path& file, const std::string& bytes) {
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

std::string le16(uint32_t v) {
  return {char(v & 0xff), char((v >> 8) & 0xff)};
}
std::string le32(uint32_t v) {
  return le16(v & 0xffff) + le16(v >> 16);
}
std::string tag_bytes(uint32_t tag) {
  return le16(tag >> 16) + le16(tag & 0xffff);
}
uint32_t read32(const std::string& b, size_t at) {
  uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

// a top-level element of a file as ITK writes it (implicit VR little endian, no sequences)
struct Element {
  uint32_t tag;
  size_t at, value_at;
  uint32_t length;
};

size_t data_set_start(const std::string& b) {
  return 132 + 12 + read32(b, 140);  // after (0002,0000) UL and the group it counts
}

std::vector<Element> elements_of(const std::string& b) {
  std::vector<Element> out;
  for (size_t at = data_set_start(b); at + 8 <= b.size();) {
    const uint32_t tag = (uint32_t(uint8_t(b[at])) | uint32_t(uint8_t(b[at + 1])) << 8) << 16 |
                         (uint32_t(uint8_t(b[at + 2])) | uint32_t(uint8_t(b[at + 3])) << 8);
    const uint32_t length = read32(b, at + 4);
    out.push_back({tag, at, at + 8, length});
    at += 8 + length;
  }
  return out;
}

// the file with element `tag` holding `value` (padded to even length), inserted in tag order
// when absent
std::string with_value(const std::string& b, uint32_t tag, std::string value) {
  if (value.size() % 2) value += ' ';
  const std::string element = tag_bytes(tag) + le32(uint32_t(value.size())) + value;
  for (const Element& e : elements_of(b)) {
    if (e.tag == tag) return b.substr(0, e.at) + element + b.substr(e.value_at + e.length);
    if (e.tag > tag) return b.substr(0, e.at) + element + b.substr(e.at);
  }
  return b + element;
}

// the file with raw element bytes inserted in tag order
std::string with_raw(const std::string& b, uint32_t tag, const std::string& raw) {
  for (const Element& e : elements_of(b))
    if (e.tag > tag) return b.substr(0, e.at) + raw + b.substr(e.at);
  return b + raw;
}

// the file with element `tag`'s length field set to `length` (nothing else changed)
std::string with_length(std::string b, uint32_t tag, uint32_t length) {
  for (const Element& e : elements_of(b))
    if (e.tag == tag) {
      std::memcpy(&b[e.at + 4], &length, 4);
      return b;
    }
  ADD_FAILURE() << fmt::format("no element {:08x}", tag);
  return b;
}

// the file's meta group with transfer syntax `uid`, its group length recounted, and the data set
// that followed the meta group (`data_set`, or the file's own)
std::string with_syntax(const std::string& b, const std::string& uid, const std::string* data_set = nullptr) {
  std::string meta;
  for (size_t at = 144; at < data_set_start(b);) {
    const uint16_t element = uint16_t(uint8_t(b[at + 2]) | uint8_t(b[at + 3]) << 8);
    const bool long_form = b.compare(at + 4, 2, "OB") == 0;
    const size_t value_at = at + (long_form ? 12 : 8);
    const size_t length = long_form ? read32(b, at + 8) : size_t(uint8_t(b[at + 6]) | uint8_t(b[at + 7]) << 8);
    if (element == 0x0010) {
      std::string v = uid;
      if (v.size() % 2) v += '\0';
      meta += tag_bytes(0x00020010) + "UI" + le16(uint32_t(v.size())) + v;
    } else {
      meta += b.substr(at, value_at + length - at);
    }
    at = value_at + length;
  }
  return b.substr(0, 132) + tag_bytes(0x00020000) + "UL" + le16(4) + le32(uint32_t(meta.size())) + meta +
         (data_set ? *data_set : b.substr(data_set_start(b)));
}

// the same file in explicit VR little endian (the VRs of the tags ITK writes; UN for any other)
std::string to_explicit(const std::string& b) {
  static const std::map<uint32_t, std::string> vr = {
      {0x00080016, "UI"}, {0x00080018, "UI"}, {0x00080020, "DA"}, {0x00080030, "TM"}, {0x00080050, "SH"},
      {0x00080060, "CS"}, {0x00080090, "PN"}, {0x00100010, "PN"}, {0x00100020, "LO"}, {0x00100030, "DA"},
      {0x00100040, "CS"}, {0x0020000d, "UI"}, {0x0020000e, "UI"}, {0x00200010, "SH"}, {0x00200011, "IS"},
      {0x00200013, "IS"}, {0x00200032, "DS"}, {0x00200037, "DS"}, {0x00200052, "UI"}, {0x00200100, "IS"},
      {0x00181060, "DS"}, {0x00180050, "DS"}, {0x00280002, "US"}, {0x00280004, "CS"}, {0x00280010, "US"},
      {0x00280011, "US"}, {0x00280030, "DS"}, {0x00280100, "US"}, {0x00280101, "US"}, {0x00280102, "US"},
      {0x00280103, "US"}, {0x00281052, "DS"}, {0x00281053, "DS"}, {0x00281054, "LO"}, {0x7fe00010, "OW"}};
  std::string data_set;
  for (const Element& e : elements_of(b)) {
    const auto it = vr.find(e.tag);
    const std::string v = it == vr.end() ? "UN" : it->second;
    data_set += tag_bytes(e.tag) + v;
    data_set += (v == "OW" || v == "UN") ? le16(0) + le32(e.length) : le16(e.length);
    data_set += b.substr(e.value_at, e.length);
  }
  return with_syntax(b, "1.2.840.10008.1.2.1", &data_set);
}

class DicomHostile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pcisim-dicom-hostile-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // 6 x 5 pixels of 0.5 x 0.6 mm, 4 axial slices 2 mm apart
    for (int k = 0; k < kSlices; ++k) {
      testing::DicomSlice s;
      s.file = file(k).string();
      s.series_uid = kSeries;
      s.study_uid = "1.2.826.0.1.3680043.2.1125.4";
      s.instance = k + 1;
      s.position_mm = {-10.0, 20.0, 30.0 + 2.0 * k};
      s.orientation = {1, 0, 0, 0, 1, 0};
      s.pixel_spacing_mm = {0.6, 0.5};
      s.slice_thickness_mm = 2.0;
      std::vector<int16_t> hu(kColumns * kRows);
      for (size_t i = 0; i < hu.size(); ++i) hu[i] = int16_t(-100 + 10 * int(i) + k);
      testing::write_dicom_slice(s, kColumns, kRows, hu);
      pristine_[k] = test::file_text(file(k));
    }
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path file(int k) const { return dir_ / fmt::format("slice_{}.dcm", k); }
  // slice k (2 unless named) rewritten from its good bytes by `change`
  template <class F>
  void corrupt(F&& change, int k = 2) {
    put(file(k), change(pristine_.at(k)));
  }
  // every slice in explicit VR little endian, from now on
  void all_explicit() {
    for (auto& [k, b] : pristine_) put(file(k), b = to_explicit(b));
  }
  // the refusal of reading the folder. The clock is a hang guard, not a speed target: a refusal takes
  // milliseconds, a hostile length that made the reader loop took minutes; 10 s leaves room for a busy
  // machine under ASan (docs/benchmarks hold speed, not unit tests)
  std::string refusal() const {
    const auto start = std::chrono::steady_clock::now();
    std::string why;
    try {
      read_dicom_series(dir_.string());
    } catch (const DicomError& e) {
      why = e.what();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(seconds, 10.0) << why;
    EXPECT_FALSE(why.empty()) << "the series was read";
    return why;
  }
  // the refusal names the file (by its whole path) and says `what`
  void expect_refused(const std::string& why, const fs::path& f, const std::string& what) const {
    EXPECT_NE(why.find(f.string() + ": " + what), std::string::npos) << why;
  }
  fs::path dir_;
  std::map<int, std::string> pristine_;
};

TEST_F(DicomHostile, TheGoodSeriesReadsInBothLittleEndianSyntaxes) {
  const Volume v = read_dicom_series(dir_.string());
  EXPECT_EQ(v.dims, (std::array<int64_t, 3>{kColumns, kRows, kSlices}));
  EXPECT_NEAR(v.spacing_mm.z(), 2.0, 1e-9);
  all_explicit();
  const Volume e = read_dicom_series(dir_.string());
  EXPECT_EQ(e.dims, v.dims);
  EXPECT_EQ(e.hu_i16, v.hu_i16);
}

// stray files that are not DICOM (no "DICM" after a 128-byte preamble) are skipped as before
TEST_F(DicomHostile, StrayFilesThatAreNotDicomAreSkipped) {
  put(dir_ / "README.txt", "exported by a workstation\n");
  put(dir_ / ".DS_Store", std::string(200, '\0'));
  put(dir_ / "empty", "");
  fs::create_directories(dir_ / "subfolder");
  EXPECT_EQ(read_dicom_series(dir_.string()).dims[2], kSlices);
}

// was SIGABRT: gdcmReader.cxx:385 assertion (while GDCM listed the folder)
TEST_F(DicomHostile, APreambleOnlyFileIsRefused) {
  put(dir_ / "preamble_only.dcm", std::string(128, '\0') + "DICM");
  expect_refused(refusal(), dir_ / "preamble_only.dcm",
                 "FileMetaInformationGroupLength (0002,0000): missing (the file ends after the preamble)");
}

// was SIGABRT after ~20 s: gdcmFileMetaInformation.cxx:591 assertion
TEST_F(DicomHostile, AnElementLengthPastTheEndIsRefused) {
  corrupt([](const std::string& b) { return with_length(b, 0x00080060, 0xFFFFFFF0u); });
  expect_refused(refusal(), file(2), "Modality (0008,0060): length 4294967280 runs past the end of the file");
  // the same in explicit VR (a 16-bit length), and in the meta group's length
  all_explicit();
  corrupt([](std::string b) {
    const size_t at = b.find(tag_bytes(0x00080060) + "CS");
    b[at + 6] = b[at + 7] = char(0xF0);
    return b;
  });
  expect_refused(refusal(), file(2), "Modality (0008,0060): length 61680 runs past the end of the file");
  corrupt([](std::string b) {
    const uint32_t huge = 0xFFFFFFF0u;
    std::memcpy(&b[140], &huge, 4);  // (0002,0000)'s value
    return b;
  });
  expect_refused(refusal(), file(2), "FileMetaInformationGroupLength (0002,0000): 4294967280");
}

// in every slice, was SIGABRT: vnl_matrix.hxx:1189 "matrix has non-finite elements" (the slices
// are evenly spaced, 1e307 mm apart: ITK's series reader computed an infinite spacing); in one
// slice GDCM's listing dropped the file and the series was refused for a gap elsewhere
TEST_F(DicomHostile, APositionOfOneE308IsRefused) {
  corrupt([](const std::string& b) { return with_value(b, 0x00200032, "0\\0\\1e308"); });
  expect_refused(refusal(), file(2), "ImagePositionPatient (0020,0032): 1e+308 mm is beyond +-100000 mm");
  for (int k = 0; k < kSlices; ++k)
    corrupt([&](const std::string& b) { return with_value(b, 0x00200032, fmt::format("0\\0\\{}e307", k + 1)); }, k);
  expect_refused(refusal(), file(0), "ImagePositionPatient (0020,0032): 1e+307 mm is beyond +-100000 mm");
}

TEST_F(DicomHostile, NumbersThatAreNotFiniteAreRefused) {
  for (const char* text : {"0\\nan\\0", "0\\0\\inf", "0\\0\\1e999", "0\\0\\x", "0\\0"}) {
    corrupt([&](const std::string& b) { return with_value(b, 0x00200032, text); });
    expect_refused(refusal(), file(2), "ImagePositionPatient (0020,0032): ");
  }
  corrupt([](const std::string& b) { return with_value(b, 0x00200037, "1\\0\\0\\0\\nan\\0"); }, 1);
  expect_refused(refusal(), file(1), "ImageOrientationPatient (0020,0037): ");
}

TEST_F(DicomHostile, ZeroNegativeOrHugePixelSpacingIsRefused) {
  for (const char* text : {"0\\0.5", "-0.6\\0.5", "0.6\\1e300", "0.6\\0.0000001"}) {
    corrupt([&](const std::string& b) { return with_value(b, 0x00280030, text); });
    expect_refused(refusal(), file(2), "PixelSpacing (0028,0030): ");
  }
}

// slices 1e4 mm apart would make a voxel 1e4 mm deep; the positions are within bounds
TEST_F(DicomHostile, AHugeSliceSpacingIsRefused) {
  for (int k = 0; k < kSlices; ++k)
    corrupt([&](const std::string& b) { return with_value(b, 0x00200032, fmt::format("0\\0\\{}", 2e4 * k)); }, k);
  const std::string why = refusal();
  EXPECT_NE(why.find(dir_.string() + ": slice spacing 20000 mm, over the 100 mm limit"), std::string::npos) << why;
}

TEST_F(DicomHostile, ANonOrthogonalOrNonUnitOrientationIsRefused) {
  corrupt([](const std::string& b) { return with_value(b, 0x00200037, "1\\0\\0\\0.7071\\0.7071\\0"); });
  expect_refused(refusal(), file(2),
                 "ImageOrientationPatient (0020,0037): row and column directions are not orthogonal (cosine 0.7071");
  corrupt([](const std::string& b) { return with_value(b, 0x00200037, "2\\0\\0\\0\\1\\0"); });
  expect_refused(refusal(), file(2), "ImageOrientationPatient (0020,0037): the row direction's length is 2");
  corrupt([](const std::string& b) { return with_value(b, 0x00200037, "0\\0\\0\\0\\1\\0"); });
  expect_refused(refusal(), file(2), "ImageOrientationPatient (0020,0037): the row direction's length is 0");
}

TEST_F(DicomHostile, TruncatedOrMismatchedPixelDataIsRefused) {
  corrupt([](const std::string& b) { return b.substr(0, b.size() - 10); });
  expect_refused(refusal(), file(2), "PixelData (7FE0,0010): length 60 runs past the end of the file");
  // a whole, shorter pixel data element: 50 bytes where 6 x 5 pixels of 16 bits need 60
  corrupt([](const std::string& b) { return with_value(b, 0x7fe00010, std::string(50, '\1')); });
  expect_refused(refusal(), file(2),
                 "PixelData (7FE0,0010): 50 bytes, Rows x Columns x NumberOfFrames x "
                 "BitsAllocated/8 is 5 x 6 x 1 x 16/8 = 60");
  corrupt([](const std::string& b) { return with_value(b, 0x00280010, std::string("\0\0", 2)); });
  expect_refused(refusal(), file(2), "Rows (0028,0010): 0");
}

// a sequence nested 100 deep (undefined lengths all the way down) in a private element
TEST_F(DicomHostile, DeepSequenceNestingIsRefused) {
  std::string nest;
  for (int d = 0; d < 100; ++d)
    nest += tag_bytes(0x00091010) + le32(0xFFFFFFFFu) + tag_bytes(0xFFFEE000) + le32(0xFFFFFFFFu);
  for (int d = 0; d < 100; ++d) nest += tag_bytes(0xFFFEE00D) + le32(0) + tag_bytes(0xFFFEE0DD) + le32(0);
  corrupt([&](const std::string& b) { return with_raw(b, 0x00091010, nest); });
  expect_refused(refusal(), file(2),
                 fmt::format("(0009,1010): sequences nested deeper than {}", dicom::kMaxSequenceDepth));
}

// an undefined length whose value is not an item, and an item that never ends
TEST_F(DicomHostile, UndefinedLengthJunkIsRefused) {
  corrupt([](const std::string& b) {
    return with_raw(b, 0x00091010, tag_bytes(0x00091010) + le32(0xFFFFFFFFu) + "junk junk junk junk ");
  });
  expect_refused(refusal(), file(2),
                 "(0009,1010): (756A,6B6E) where an item (FFFE,E000) or the sequence's end belongs");
  corrupt([](const std::string& b) {
    return b + tag_bytes(0x7fe10010) + le32(0xFFFFFFFFu) + tag_bytes(0xFFFEE000) + le32(0xFFFFFFFFu) +
           tag_bytes(0x00100010) + le32(4) + "ABCD";
  });
  expect_refused(refusal(), file(2), "Item (FFFE,E000): of undefined length never ends");
}

// GDCM reads RescaleSlope as a DS attribute and asserted on another explicit VR: SIGABRT,
// gdcmAttribute.h:445 "GetVR().Compatible(de.GetVR())" (found by replaying mutants through GDCM;
// fuzz/corpus/dicom/rescale_slope_vr_us.dcm)
TEST_F(DicomHostile, AnExplicitVrGdcmReadsAsAnotherTypeIsRefused) {
  all_explicit();
  corrupt([](std::string b) {
    const size_t at = b.find(tag_bytes(0x00281053) + "DS");
    b.replace(at + 4, 2, "US");  // its value "1 " is two bytes: a well-formed US
    return b;
  });
  expect_refused(refusal(), file(2), "RescaleSlope (0028,1053): VR US, must be DS");
}

TEST_F(DicomHostile, CompressedAndUnknownTransferSyntaxesAreRefusedByName) {
  for (const auto& [uid, name] : std::map<std::string, std::string>{
           {"1.2.840.10008.1.2.4.90", "JPEG 2000 Image Compression (Lossless Only) (1.2.840.10008.1.2.4.90)"},
           {"1.2.840.10008.1.2.2", "Explicit VR Big Endian (1.2.840.10008.1.2.2)"},
           {"1.2.3.4", "an unknown transfer syntax (1.2.3.4)"}}) {
    corrupt([&](const std::string& b) { return with_syntax(b, uid); });
    expect_refused(refusal(), file(2), "TransferSyntaxUID (0002,0010): " + name + " is not accepted");
  }
}

// the header walk straight on bytes, as the fuzz target runs it: cut at every length, a good file
// is refused (a DicomError naming the file), never passed short
TEST_F(DicomHostile, EveryPrefixOfAGoodFileIsRefused) {
  const std::string b = test::file_text(file(0));
  EXPECT_EQ(dicom::precheck_dicom("good.dcm", b).series_uid, kSeries);
  for (size_t n = 0; n < b.size(); ++n) {
    try {
      dicom::precheck_dicom("cut.dcm", b.substr(0, n));
      ADD_FAILURE() << "passed cut at " << n;
    } catch (const DicomError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("cut.dcm: ", 0), 0u) << e.what();
    }
  }
}

// the fuzz target's corpus (fuzz/corpus/dicom/; or the folder in PCISIM_DICOM_REPLAY, e.g. a
// fuzzing run's working corpus) through GDCM and ITK as the series reader hands a file over: the
// fuzz build cannot link GDCM (Debian's ITK headers refuse clang), so this replays what the walk
// passes. A GDCM assertion ends the process: a file the walk must learn to refuse.
TEST(DicomFuzzCorpus, NeverAbortsGdcm) {
  const char* replay = std::getenv("PCISIM_DICOM_REPLAY");
  const fs::path folder = replay ? fs::path(replay) : fs::path(PCISIM_SOURCE_DIR) / "fuzz/corpus/dicom";
  int passed = 0, files = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    ++files;
    const std::string file = entry.path().string();
    try {
      if (dicom::precheck_dicom_file(file).dicomdir) continue;
    } catch (const DicomError&) {
      continue;
    }
    ++passed;
    if (replay) std::fprintf(stderr, "through GDCM: %s\n", file.c_str());  // the last one, if it aborts
    try {
      (void)itk_io::read_tags(file, {"0020|0032", "0020|0037", "0028|0030", "0028|0010"});
      itk_io::read_voxels({file}, [](const std::array<int64_t, 3>&, const float*) {});
    } catch (const std::runtime_error&) {}
  }
  if (!replay) EXPECT_GE(passed, 2) << "the seeds (a CT slice in each little-endian syntax) pass the walk";
  std::printf("%d of %d files passed the walk and went through GDCM\n", passed, files);
}

}  // namespace
}  // namespace pcisim::anatomy
