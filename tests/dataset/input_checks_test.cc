// What a dataset spec names is checked before the first sample: a trainee script that is no
// script, a projector that cannot run here, a case folder that cannot be read are each refused
// naming the spec file and the field, instead of failing every sample.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#if defined(PCISIM_DATASET_HAVE_SCRIPTS)
#include "clients/bridge/trainee_script.h"
#endif
#include "dataset/run/input_checks.h"
#include "dataset/sample/sample_plan.h"
#include "dataset/spec/dataset_spec.h"
#include "json/json_reader.h"

namespace pcisim::dataset {
namespace {

namespace fs = std::filesystem;

class InputChecks : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pcisim-input-checks-" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // the refusal of the spec `text` (its folder dir_), "" when it and what it names are accepted
  std::string refusal(const std::string& text) {
    try {
      check_spec_inputs(parse_dataset_spec(text, "spec.json", dir_.string()));
    } catch (const json::JsonError& e) {
      return e.what();
    }
    return "";
  }
  static std::string script_spec(const std::string& second) {
    return R"({"samples": 2, "driver": {"kind": "script", "scripts": ["builtin", ")" + second + R"("]}})";
  }

  fs::path dir_;
};

#if defined(PCISIM_DATASET_HAVE_SCRIPTS)
TEST_F(InputChecks, ATraineeScriptThatIsNoScriptIsRefusedNamingItsPlace) {
  std::ofstream(dir_ / "good.json") << clients::TraineeScript::builtin_text();
  EXPECT_EQ(refusal(script_spec("good.json")), "");

  fs::create_directories(dir_ / "folder");
  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  const std::string at = "spec.json: driver.scripts[1]: ";
  EXPECT_EQ(refusal(script_spec("missing.json")),
            at + (dir_ / "missing.json").string() + ": cannot open the trainee script: No such file or directory");
  EXPECT_EQ(refusal(script_spec("folder")),
            at + (dir_ / "folder").string() + ": not a regular file (a folder, never read as the trainee script)");
  EXPECT_EQ(refusal(script_spec("fifo")),
            at + (dir_ / "fifo").string() + ": not a regular file (a FIFO, never read as the trainee script)");
  EXPECT_EQ(refusal(script_spec("/dev/zero")),
            at + "/dev/zero: not a regular file (a character device, never read as the trainee script)");
  const std::string passwd = refusal(script_spec("/etc/passwd"));
  EXPECT_EQ(passwd.rfind(at + "/etc/passwd: not valid JSON", 0), 0u) << passwd;
}
#endif

TEST_F(InputChecks, AProjectorThatCannotRunHereIsRefused) {
  EXPECT_EQ(refusal(R"({"samples": 2, "projector": "cpu"})"), "");
  const std::string cuda = projector_problem(xray::ProjectorKind::kCudaTrilinear);
  if (cuda.empty()) GTEST_SKIP() << "a GPU answers here: the cuda projector can run";
  EXPECT_EQ(refusal(R"({"samples": 2, "projector": "cuda"})"),
            "spec.json: projector: \"cuda\" cannot run here: " + cuda);
  // the scene's projector, picked by a varied value, taken by "scene"
  const std::string varied = refusal(
      R"({"samples": 2, "projector": "scene", "vary": {"effects.xray.projector": {"choice": ["cpu", "cuda"]}}})");
  EXPECT_EQ(varied.rfind("spec.json: vary.effects.xray.projector = \"cuda\": the scene's projector \"cuda\"", 0), 0u)
      << varied;
  // "auto" without a GPU takes the scene's, which then may not run either
  std::ofstream(dir_ / "scene.json") << R"({"effects": {"xray": {"projector": "cuda"}}})";
  const std::string from_scene = refusal(R"({"samples": 2, "scene": "scene.json", "projector": "auto"})");
  EXPECT_EQ(from_scene.rfind("spec.json: scene: the scene's projector \"cuda\"", 0), 0u) << from_scene;
}

TEST_F(InputChecks, ACaseFolderThatCannotBeReadIsRefusedNamingItsPlace) {
  fs::create_directories(dir_ / "bad");
  std::ofstream(dir_ / "bad" / "case.json") << R"({"format": "pcisim-case"})";
  const std::string r = refusal(R"({"samples": 2, "anatomy": {"phantom_seeds": {"choice": [1]}, "cases": ["bad"]}})");
  EXPECT_EQ(r.rfind("spec.json: anatomy.cases[0]: " + (dir_ / "bad" / "case.json").string() + ": ", 0), 0u) << r;
}

}  // namespace
}  // namespace pcisim::dataset
