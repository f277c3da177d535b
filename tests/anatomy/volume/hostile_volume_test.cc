// Volume headers as a careless user or a hostile file would write them (found by fuzzing
// pcisim-drr): sizes that overflow, a header that claims far more than its data, data files that
// are a FIFO or a device, non-finite voxels. Each is refused naming the file and the field,
// before anything is allocated for the claimed size and without blocking.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <string>
#include <thread>

#include "realtime/allocation_count.h"
#include "anatomy/volume/volume_io.h"

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

class HostileVolume : public ::testing::Test {
 protected:
  fs::path dir = fs::path(::testing::TempDir()) / ("pcisim-hostile-volume-" + std::to_string(::getpid()));
  void SetUp() override { fs::create_directories(dir); }
  void TearDown() override { fs::remove_all(dir); }

  std::string write(const std::string& name, const std::string& text) {
    const std::string path = (dir / name).string();
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  // the refusal's message; fails the test when the file is accepted or allocates its claim
  std::string refusal(const std::string& path) {
    pcisim::realtime::AllocationCount alloc;
    try {
      read_volume(path);
    } catch (const VolumeIoError& e) {
      EXPECT_LT(alloc.largest(), 1 << 20) << path << ": allocated for the claimed size before refusing";
      return e.what();
    }
    ADD_FAILURE() << path << " was accepted";
    return {};
  }
};

std::string mha(const std::string& dims, const std::string& type = "MET_SHORT",
                const std::string& data_file = "LOCAL") {
  return "ObjectType = Image\nNDims = 3\nDimSize = " + dims + "\nElementType = " + type +
         "\nElementDataFile = " + data_file + "\n";
}

std::string nrrd(const std::string& sizes, const std::string& extra = "") {
  return "NRRD0004\ntype: short\ndimension: 3\nsizes: " + sizes + "\nencoding: raw\nendian: little\n" + extra + "\n";
}

// 2305843009213693953 x 8 x 1 voxels x 2 bytes wraps to 16 bytes: accepted, then SIGSEGV
TEST_F(HostileVolume, SizesWhoseProductOverflowsAreRefused) {
  const std::string data(16, '\0');
  EXPECT_NE(refusal(write("a.mha", mha("2305843009213693953 8 1") + data)).find("a.mha: DimSize:"), std::string::npos);
  EXPECT_NE(refusal(write("b.nrrd", nrrd("2305843009213693953 8 1") + data)).find("b.nrrd: sizes:"), std::string::npos);
}

// 4294967296 x 4294967296 x 1 wrapped to 0 voxels and was accepted (null to memcpy)
TEST_F(HostileVolume, SizesOverTheVoxelLimitAreRefused) {
  const std::string m = refusal(write("c.mha", mha("4294967296 4294967296 1")));
  EXPECT_NE(m.find("c.mha: DimSize: 4294967296 x 4294967296 x 1 voxels: over the"), std::string::npos) << m;
  EXPECT_NE(refusal(write("d.nrrd", nrrd("4294967296 4294967296 1"))).find("d.nrrd: sizes:"), std::string::npos);
}

// a 316-byte file claiming 512^3 voxels reached 6.3 GB before it was refused
TEST_F(HostileVolume, AHeaderClaimingMoreThanItsDataIsRefusedBeforeAllocating) {
  const std::string m = refusal(write("e.mha", mha("512 512 512") + std::string(100, '\0')));
  EXPECT_NE(m.find("e.mha: DimSize: 512x512x512 int16 voxels need 268435456 bytes"), std::string::npos) << m;
  const std::string gz = refusal(write("f.nrrd",
                                       "NRRD0004\ntype: short\ndimension: 3\nsizes: 1024 1024 512\n"
                                       "encoding: gzip\n\n" +
                                           std::string(64, 'x')));
  EXPECT_NE(gz.find("f.nrrd: sizes: 1073741824 voxel bytes cannot come from 64 compressed bytes"), std::string::npos)
      << gz;
}

// a FIFO as the data file blocked the reader for ever; /dev/zero read 2 GB
TEST_F(HostileVolume, ADataFileThatIsAFifoOrADeviceIsRefusedWithoutBlocking) {
  const std::string fifo = (dir / "voxels.raw").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string header = write("g.mhd", mha("2 2 2", "MET_SHORT", "voxels.raw"));
  auto read = std::async(std::launch::async, [&] { return refusal(header); });
  if (read.wait_for(10s) != std::future_status::ready) {
    std::ofstream unblock(fifo);  // lets the reader go before the test fails
    FAIL() << "the reader blocked on a FIFO";
  }
  EXPECT_NE(read.get().find("g.mhd: ElementDataFile: cannot open"), std::string::npos);
  const std::string zero = refusal(write("h.nhdr", nrrd("2 2 2", "data file: /dev/zero")));
  EXPECT_NE(zero.find("not a regular file"), std::string::npos) << zero;
}

// NaN and infinite voxels made every ray through them NaN, and pcisim-drr exited 0
TEST_F(HostileVolume, NonFiniteVoxelsAreRefusedNamingTheVoxel) {
  float voxels[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  voxels[5] = std::nanf("");
  const std::string m =
      refusal(write("i.mha", mha("2 2 2", "MET_FLOAT") + std::string(reinterpret_cast<char*>(voxels), sizeof voxels)));
  EXPECT_NE(m.find("i.mha: voxels: voxel (1, 0, 1) is nan"), std::string::npos) << m;
  voxels[5] = 0;
  voxels[7] = INFINITY;
  const std::string inf =
      refusal(write("j.mha", mha("2 2 2", "MET_FLOAT") + std::string(reinterpret_cast<char*>(voxels), sizeof voxels)));
  EXPECT_NE(inf.find("voxel (1, 1, 1) is inf"), std::string::npos) << inf;
}

}  // namespace
}  // namespace pcisim::anatomy
