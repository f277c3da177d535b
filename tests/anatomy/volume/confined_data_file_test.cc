// A volume read from a case folder (DataFileScope::kHeaderFolder) reads its detached data file
// only from the folder that holds its header: an absolute path, "..", or a symbolic link leading
// out is refused naming the header and the field, before the file is opened. A volume the user
// names (the default, kAnywhere) still follows any path, as the command-line tools expect.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "anatomy/volume/inside_folder.h"
#include "anatomy/volume/volume_io.h"

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;

class ConfinedDataFile : public ::testing::Test {
 protected:
  // root/case holds the headers; root/outside the bytes a hostile header points at: valid voxels,
  // so the only refusal can come from where they lie
  fs::path root = fs::path(::testing::TempDir()) / ("pcisim-confined-" + std::to_string(::getpid()) + "-" +
                                                    ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::path case_dir = root / "case", outside = root / "outside";
  void SetUp() override {
    fs::remove_all(root);
    fs::create_directories(case_dir / "data");
    fs::create_directories(outside);
    write(outside / "secret.raw", voxels());
    write(case_dir / "data" / "ct.raw", voxels());
  }
  void TearDown() override { fs::remove_all(root); }

  static std::string voxels() { return std::string(2 * 2 * 1 * sizeof(int16_t), '\1'); }
  static void write(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }
  // a header in the case folder whose data file is `data_file`
  std::string nhdr(const std::string& data_file) const {
    const fs::path p = case_dir / "ct.nhdr";
    write(p,
          "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 1\nspacings: 1 1 1\nencoding: raw\nendian: little\n"
          "data file: " +
              data_file + "\n");
    return p.string();
  }
  std::string mhd(const std::string& data_file) const {
    const fs::path p = case_dir / "ct.mhd";
    write(p,
          "ObjectType = Image\nNDims = 3\nDimSize = 2 2 1\nElementSpacing = 1 1 1\nElementType = MET_SHORT\n"
          "ElementDataFile = " +
              data_file + "\n");
    return p.string();
  }
  // the refusal's message when read from a case; "" when read
  static std::string refusal(const std::string& header) {
    try {
      read_volume(header, true, DataFileScope::kHeaderFolder);
    } catch (const VolumeIoError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(ConfinedDataFile, AnAbsoluteOrParentPathIsRefusedFromACaseAndFollowedOtherwise) {
  const std::string secret = (outside / "secret.raw").string();
  for (const auto& [header, field] :
       {std::pair{nhdr(secret), "ct.nhdr: data file: '"}, std::pair{mhd(secret), "ct.mhd: ElementDataFile: '"}}) {
    EXPECT_NE(refusal(header).find(field + secret + "' is an absolute path"), std::string::npos) << refusal(header);
    EXPECT_EQ(read_volume(header, true).voxel_count(), 4) << header;  // a user's own volume: any path
  }
  for (const auto& [header, field] : {std::pair{nhdr("../outside/secret.raw"), "ct.nhdr: data file: '"},
                                      std::pair{mhd("../outside/secret.raw"), "ct.mhd: ElementDataFile: '"}}) {
    EXPECT_NE(refusal(header).find(std::string(field) + "../outside/secret.raw' goes up with '..'"), std::string::npos)
        << refusal(header);
    EXPECT_EQ(read_volume(header, true).voxel_count(), 4) << header;
  }
}

TEST_F(ConfinedDataFile, ASymbolicLinkLeadingOutIsRefused) {
  // a link to the file, and a link to a folder holding it; and a sibling folder whose name
  // begins with the case's ("case-2"): the prefix is compared by component, not by character
  fs::create_directories(root / "case-2");
  write(root / "case-2" / "x.raw", voxels());
  fs::create_symlink(outside / "secret.raw", case_dir / "link.raw");
  fs::create_symlink(outside, case_dir / "linked");
  fs::create_symlink(root / "case-2" / "x.raw", case_dir / "sibling.raw");
  for (const std::string name : {"link.raw", "linked/secret.raw", "sibling.raw"}) {
    for (const std::string& header : {nhdr(name), mhd(name)}) {
      const std::string why = refusal(header);
      EXPECT_NE(why.find("'" + name + "' leads to '"), std::string::npos) << why;
      EXPECT_NE(why.find("through a symbolic link, outside the folder"), std::string::npos) << why;
      EXPECT_EQ(read_volume(header, true).voxel_count(), 4) << header;
    }
  }
  // a link to /dev/zero says what it leads to, and is never opened
  fs::create_symlink("/dev/zero", case_dir / "zero.raw");
  EXPECT_NE(refusal(nhdr("zero.raw")).find("leads to '/dev/zero' (a character device) through a symbolic link"),
            std::string::npos)
      << refusal(nhdr("zero.raw"));
}

TEST_F(ConfinedDataFile, AFileInsideTheHeadersFolderIsRead) {
  // in a subfolder, through "./", or through a link that stays inside
  fs::create_symlink("data/ct.raw", case_dir / "inside.raw");
  for (const std::string name : {"data/ct.raw", "./data/ct.raw", "inside.raw"}) {
    EXPECT_EQ(refusal(nhdr(name)), "") << name;
    EXPECT_EQ(refusal(mhd(name)), "") << name;
  }
}

TEST_F(ConfinedDataFile, AControlCharacterInTheNameIsRefusedShowingIt) {
  const std::string why = refusal(nhdr(std::string("data/ct.raw\x01x")));
  EXPECT_NE(why.find("ct.nhdr: data file: 'data/ct.raw\\u0001x' holds a control character"), std::string::npos) << why;
}

TEST(InsideFolder, ResolvesOnlyNamesThatStayInside) {
  const fs::path root = fs::path(::testing::TempDir()) / ("pcisim-inside-" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "a" / "b");
  fs::create_directories(root / "ab");
  fs::create_symlink(root / "ab", root / "a" / "up");
  fs::create_symlink("missing-target", root / "a" / "dangling");
  const std::string a = (root / "a").string();
  EXPECT_EQ(resolve_inside_folder(a, "b/new.txt").escape, FolderEscape::kNone);  // missing but inside
  EXPECT_EQ(resolve_inside_folder(a, "b/new.txt").resolved, fs::canonical(root / "a" / "b").string() + "/new.txt");
  EXPECT_EQ(resolve_inside_folder(a, "up/x").escape, FolderEscape::kThroughLink);  // root/ab is not inside root/a
  EXPECT_EQ(resolve_inside_folder(a, "dangling").escape, FolderEscape::kThroughLink);
  EXPECT_EQ(resolve_inside_folder(a, "b/../../x").escape, FolderEscape::kNotRelative);
  EXPECT_EQ(resolve_inside_folder(a, "").escape, FolderEscape::kNotRelative);
  EXPECT_EQ(resolve_inside_folder(a, std::string("b\0x", 3)).escape, FolderEscape::kControlCharacter);
  EXPECT_EQ(escaped_name(std::string("b\0x\n", 4)), "b\\u0000x\\u000a");
  fs::remove_all(root);
}

}  // namespace
}  // namespace pcisim::anatomy
