// pcisim-drr end to end: argument errors name the argument; a render matches the library.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

#include "xray/projectors/siddon_projector.h"
#include "anatomy/volume/volume_io.h"

namespace pcisim::xray {
namespace {

namespace fs = std::filesystem;

const std::string kTool = PCISIM_BINARY_DIR "/xray/pcisim-drr";

struct Result {
  int rc;
  std::string err;
};

Result run_tool(const std::string& args) {
  const fs::path err = fs::temp_directory_path() / ("pcisim_drr_err_" + std::to_string(::getpid()));
  const int status = std::system((kTool + " " + args + " > /dev/null 2> " + err.string()).c_str());
  std::ifstream f(err);
  std::stringstream ss;
  ss << f.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ss.str()};
}

class DrrTool : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kTool)) GTEST_SKIP() << kTool << " is not built (ninja pcisim-drr)";
    dir_ = fs::temp_directory_path() / ("pcisim_drr_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  fs::path dir_;
};

TEST_F(DrrTool, BadArgumentsNameTheArgument) {
  const std::string geo = "--source 0,500,0 --detector-center 0,-300,0 --detector-u 1,0,0 --detector-v 0,0,-1 ";
  const struct {
    std::string args, expect;
  } cases[] = {
      {"--volume v.mha " + geo + "--pixel-mm 1 --size 512 --projector exact --out x", "--size: expected W,H"},
      {geo + "--pixel-mm 1 --size 4,4 --projector exact --out x", "--volume: missing"},
      {"--volume v.mha " + geo + "--pixel-mm 1 --size 4,4 --projector fast --out x",
       "--projector: expected exact, cpu, gl or cuda, got 'fast'"},
      {"--volume v.mha " + geo + "--pixel-mm -1 --size 4,4 --projector cpu --out x",
       "--pixel-mm: expected a number > 0, got '-1'"},
      {"--volume v.mha --source 0,500 --detector-center 0,-300,0 --detector-u 1,0,0 --detector-v 0,0,-1 "
       "--pixel-mm 1 --size 4,4 --projector cpu --out x",
       "--source: expected three numbers x,y,z, got '0,500'"},
      {"--volume v.mha --source 0,500,0 --detector-center 0,-300,0 --detector-u 1,0,0 --detector-v 1,0,0 "
       "--pixel-mm 1 --size 4,4 --projector cpu --out x",
       "--detector-v: expected a vector perpendicular to --detector-u"},
      {"--volume v.mha " + geo + "--pixel-mm 1 --size 4,4 --projector exact --step 1 --out x",
       "--step: only used by the cpu, gl and cuda projectors"},
      {"--volume /nonexistent/v.mha " + geo + "--pixel-mm 1 --size 4,4 --projector exact --out x",
       "--volume: /nonexistent/v.mha: cannot open the file: No such file or directory"},
      {"--frobnicate", "--frobnicate: unknown argument"},
      {"--write-phantom p.mha --size 4,4", "--size: expected X,Y,Z"},
  };
  for (const auto& c : cases) {
    const Result r = run_tool(c.args);
    EXPECT_EQ(r.rc, 2) << c.args;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n got: " << r.err;
  }
}

TEST_F(DrrTool, RenderMatchesTheLibraryAndWritesTheSidecar) {
  const std::string vol = (dir_ / "ph.mha").string(), out = (dir_ / "frame").string();
  ASSERT_EQ(run_tool("--write-phantom " + vol + " --size 40,36,20 --spacing 8 --seed 4").rc, 0);
  const std::string args = "--volume " + vol +
                           " --source 10,600,20 --detector-center -5,-400,0 --detector-u 1,0,0 --detector-v 0,0,-1"
                           " --pixel-mm 30 --size 9,7 --projector exact --out " +
                           out;
  const Result r = run_tool(args);
  ASSERT_EQ(r.rc, 0) << r.err;
  ASSERT_EQ(fs::file_size(out + ".f32"), 9u * 7u * 4u);
  std::vector<float> got(9 * 7);
  std::ifstream(out + ".f32", std::ios::binary).read(reinterpret_cast<char*>(got.data()), got.size() * 4);

  const anatomy::Volume v = anatomy::read_volume(vol);
  const AttenuationVolume a(v);
  DetectorGeometry g;
  g.source_mm = {10, 600, 20};
  g.center_mm = {-5, -400, 0};
  g.u = {1, 0, 0};
  g.v = {0, 0, -1};
  g.pixel_mm = 30;
  g.width = 9;
  g.height = 7;
  float peak = 0;
  for (int row = 0; row < 7; ++row) {
    for (int c = 0; c < 9; ++c) {
      const double want = exact_line_integral(a, g.source_mm, g.pixel_center_mm(c, row));
      peak = std::max(peak, float(want));
      EXPECT_NEAR(got[row * 9 + c], want, 1e-5 * std::max(1.0, want)) << c << "," << row;
    }
  }
  EXPECT_GT(peak, 1.0f);  // the rays cross the body
  std::ifstream js(out + ".json");
  std::stringstream ss;
  ss << js.rdbuf();
  EXPECT_NE(ss.str().find("\"projector\": \"exact\""), std::string::npos) << ss.str();
  EXPECT_NE(ss.str().find("\"width\": 9"), std::string::npos);
}

}  // namespace
}  // namespace pcisim::xray
