// scripts/dataset-slurm on a real single-node Slurm (scripts/slurm-local: munged, slurmctld and
// slurmd with everything in a temporary folder): a 3-shard job array and its merge give every
// sample exactly once, the same set as one local run of the same spec. Skipped, saying why, where
// Slurm cannot start (not root, packages missing, a loopback-only network namespace).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/common/file_text.h"

namespace {

namespace fs = std::filesystem;

using pcisim::test::file_text;

int sh(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(DatasetSlurm, AThreeShardArrayEqualsOneLocalRun) {
  const std::string src = PCISIM_SOURCE_DIR, tool = std::string(PCISIM_BINARY_DIR) + "/dataset/pcisim-dataset";
  if (geteuid() != 0) GTEST_SKIP() << "Slurm's daemons need root here (scripts/slurm-local)";
  if (sh("command -v sbatch slurmctld slurmd munged > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "Slurm is not installed (scripts/setup installs slurmctld, slurmd, slurm-client, munge)";
  // a short path: munge's socket path is limited to 107 bytes
  char tmpl[] = "/tmp/pcisim-slurm-XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  const fs::path dir(tmpl);
  const fs::path cluster = dir / "c";
  const std::string start_log = (dir / "start.log").string();
  const int started =
      sh(src + "/scripts/slurm-local start " + cluster.string() + " > " + (dir / "env").string() + " 2> " + start_log);
  if (started == 3) {
    const std::string why = file_text(start_log);
    fs::remove_all(dir);
    GTEST_SKIP() << "Slurm cannot start here: " << why;
  }
  ASSERT_EQ(started, 0) << file_text(start_log);

  // the spec: a small scene, seven samples of two frames, varied anatomy, pose and dose
  std::ofstream(dir / "scene.json") << R"({"name": "slurm-test", "anatomy": {"phantom_seed": 1}, "effects": {
      "guidewire": {"segments": 100}, "vessel_contact": {"sdf_spacing_mm": 0.4}, "friction": {},
      "xray": {"projector": "cpu", "detector_px": 96, "pixel_mm": 2.0, "volume_voxels": 64,
               "volume_spacing_mm": 5}, "contrast": {}, "detector_noise": {"photons_per_pixel": 800}}})";
  std::ofstream(dir / "spec.json") << R"({"name": "slurm-test", "scene": "scene.json", "samples": 7,
      "frames_per_sample": 2, "seed": 4, "warmup_s": {"uniform": [0.3, 0.8]},
      "anatomy": {"phantom_seeds": {"integers": [1, 2]}},
      "vary": {"effects.xray.primary_deg": {"uniform": [-40, 40]}}})";
  const std::string spec = (dir / "spec.json").string();
  const std::string env = ". " + (dir / "env").string() + " && ";
  const int submitted =
      sh(env + src + "/scripts/dataset-slurm --spec " + spec + " --out " + (dir / "array").string() +
         " --shards 3 --cpus 1 --tool " + tool + " --wait > " + (dir / "submit.log").string() + " 2>&1");
  const int local = sh(tool + " --spec " + spec + " --out " + (dir / "local").string() + " > " +
                       (dir / "local.log").string() + " 2>&1");
  sh(src + "/scripts/slurm-local stop " + cluster.string() + " > /dev/null 2>&1");
  ASSERT_EQ(submitted, 0) << file_text(dir / "submit.log") << file_text(dir / "array" / "slurm" / "shard-0.log");
  ASSERT_EQ(local, 0) << file_text(dir / "local.log");

  const auto merged = nlohmann::json::parse(file_text(dir / "array" / "manifest.json"));
  const auto single = nlohmann::json::parse(file_text(dir / "local" / "manifest.json"));
  // every sample exactly once, made by the shard it belongs to
  std::multiset<int64_t> seen;
  for (const auto& s : merged["samples"]) seen.insert(s["sample"].get<int64_t>());
  EXPECT_EQ(seen, (std::multiset<int64_t>{0, 1, 2, 3, 4, 5, 6}));
  for (int k = 0; k < 3; ++k)
    EXPECT_TRUE(fs::exists(dir / "array" / "shards" / ("shard-" + std::to_string(k) + "-of-3.jsonl")));
  // the same set: every file of every sample, and the merged COCO file
  EXPECT_EQ(merged["samples"], single["samples"]);
  EXPECT_EQ(file_text(dir / "array" / "coco.json"), file_text(dir / "local" / "coco.json"));
  fs::remove_all(dir);
}

}  // namespace
