// pcisim-dataset's exit status says what happened: a spec naming a script that is none is refused
// before any sample (it once ran and failed every sample), and a run whose every sample failed
// does not exit 0 (it once did, saying "0 samples, 1 failed").
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/common/file_text.h"

namespace {

namespace fs = std::filesystem;

const std::string kTool = std::string(PCISIM_BINARY_DIR) + "/dataset/pcisim-dataset";

class DatasetExit : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pcisim-dataset-exit-" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // a tiny scene: 32-pixel detector over a coarse CT, few wire segments
    std::ofstream(dir_ / "scene.json") << R"({"name": "exit-test", "anatomy": {"phantom_seed": 1}, "effects": {
        "guidewire": {"segments": 20}, "vessel_contact": {"sdf_spacing_mm": 1.0},
        "xray": {"projector": "cpu", "detector_px": 32, "pixel_mm": 1.6, "volume_voxels": 32, "volume_spacing_mm": 5}}})";
  }
  void TearDown() override { fs::remove_all(dir_); }

  int run(const std::string& spec_body, const std::string& args, std::string* log) {
    std::ofstream(dir_ / "spec.json") << R"({"name": "exit", "scene": "scene.json", )" << spec_body << "}";
    const fs::path out = dir_ / "tool.log";
    const int status = std::system(
        (kTool + " --spec " + (dir_ / "spec.json").string() + " " + args + " > " + out.string() + " 2>&1").c_str());
    *log = pcisim::test::file_text(out);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  fs::path dir_;
};

TEST_F(DatasetExit, AScriptThatIsNoScriptIsRefusedBeforeAnySample) {
#if !defined(PCISIM_DATASET_HAVE_SCRIPTS)
  GTEST_SKIP() << "built without LCM: this build reads no trainee scripts";
#endif
  std::string log;
  const std::string out = (dir_ / "out").string();
  EXPECT_EQ(run(R"("samples": 1, "driver": {"kind": "script", "scripts": ["/dev/zero"]})", "--check", &log), 2) << log;
  EXPECT_NE(log.find("spec.json: driver.scripts[0]: /dev/zero: not a regular file"), std::string::npos) << log;
  EXPECT_EQ(run(R"("samples": 1, "driver": {"kind": "script", "scripts": ["/etc/passwd"]})", "--out " + out, &log), 2)
      << log;
  EXPECT_NE(log.find("spec.json: driver.scripts[0]: /etc/passwd: not valid JSON"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "samples" / ".partial-0000000")) << "a sample was started";
}

TEST_F(DatasetExit, ARunWhoseEverySampleFailedDoesNotExitZero) {
  // each value is fine alone; the source-to-axis distance above the SID is not, in every sample
  std::string log;
  const int code = run(
      R"("samples": 2, "frames_per_sample": 1, "warmup_s": 0.1,
         "vary": {"effects.xray.sid_mm": {"choice": [800]}, "effects.xray.sad_mm": {"choice": [900]}})",
      "--out " + (dir_ / "out").string(), &log);
  EXPECT_EQ(code, 6) << log;
  EXPECT_NE(log.find("every sample this run tried failed (2;"), std::string::npos) << log;
}

}  // namespace
