// Whole datasets made by the real pcisim-dataset program on small scenes: the same spec gives
// the same bytes, labels land where the documented projection puts them, a run killed mid-sample
// resumes to the same set, a failing sample is recorded and the run goes on, a full disk is
// reported with nothing half-listed.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "png/png_gray.h"
#include "tests/common/file_text.h"

namespace {

namespace fs = std::filesystem;

const std::string kTool = std::string(PCISIM_BINARY_DIR) + "/dataset/pcisim-dataset";

// a small fast scene: a 128-pixel detector over a coarse thorax, the wire in a still tree
std::string scene_text(bool beating, bool noise) {
  std::string effects =
      R"("guidewire": {"segments": 100},
         "vessel_contact": {"sdf_spacing_mm": 0.4},
         "friction": {},
         "xray": {"projector": "cpu", "detector_px": 128, "pixel_mm": 1.6, "volume_voxels": 64,
                  "volume_spacing_mm": 5, "primary_deg": -30, "secondary_deg": 30, "heart_phase_bins": 4},
         "contrast": {})";
  if (beating) effects += R"(, "heart_beat": {}, "vessel_motion": {})";
  if (noise) effects += R"(, "detector_noise": {"photons_per_pixel": 1000})";
  return R"({"name": "dataset-test", "physics_rate_hz": 30, "anatomy": {"phantom_seed": 1}, "effects": {)" + effects +
         "}}";
}

class DatasetRun : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pcisim-dataset-test-" + std::to_string(getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!getenv("PCISIM_KEEP_TEST_DIR")) fs::remove_all(dir_);
  }

  // writes the scene and a spec around it; returns the spec's path
  std::string write_spec(const std::string& name, const std::string& body, bool beating = false, bool noise = true) {
    std::ofstream(dir_ / (name + "-scene.json")) << scene_text(beating, noise);
    const fs::path spec = dir_ / (name + ".json");
    std::ofstream(spec) << R"({"name": ")" << name << R"(", "scene": ")" << name << "-scene.json\", " << body << "}";
    return spec.string();
  }

  // runs the tool, returns its exit status; its output in *log
  int run(const std::string& args, std::string* log = nullptr) {
    const fs::path out = dir_ / "tool.log";
    const int status = std::system((kTool + " " + args + " > " + out.string() + " 2>&1").c_str());
    if (log) *log = pcisim::test::file_text(out);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  static nlohmann::json read_json(const fs::path& p) {
    std::ifstream in(p);
    return nlohmann::json::parse(in);
  }

  fs::path dir_;
};

constexpr const char* kVaried = R"(
  "samples": 3, "frames_per_sample": 2, "seed": 11,
  "anatomy": {"phantom_seeds": {"integers": [1, 2]}},
  "warmup_s": {"uniform": [0.3, 0.5]},
  "contrast": {"probability": 1.0, "start_s": {"uniform": [-0.3, 0.0]}},
  "vary": {"effects.xray.primary_deg": {"uniform": [-40, 40]},
           "effects.detector_noise.photons_per_pixel": {"log_uniform": [500, 3000]}})";

TEST_F(DatasetRun, TheSameSpecGivesTheSameBytesWhateverTheJobs) {
  const std::string spec = write_spec("same", kVaried, /*beating=*/true);
  std::string log;
  ASSERT_EQ(run("--spec " + spec + " --out " + (dir_ / "a").string(), &log), 0) << log;
  // the second with two jobs: a sample depends on its number alone
  ASSERT_EQ(run("--spec " + spec + " --out " + (dir_ / "b").string() + " --jobs 2", &log), 0) << log;
  const auto a = read_json(dir_ / "a" / "manifest.json"), b = read_json(dir_ / "b" / "manifest.json");
  ASSERT_EQ(a["samples"].size(), 3u);
  EXPECT_EQ(a["frames"], 6);
  EXPECT_EQ(a["samples"], b["samples"]);  // every sample's digest of every file
  EXPECT_EQ(pcisim::test::file_text(dir_ / "a" / "coco.json"), pcisim::test::file_text(dir_ / "b" / "coco.json"));
  // and the samples differ from each other (their draws, their noise)
  EXPECT_NE(a["samples"][0]["digest"], a["samples"][1]["digest"]);
  // the progress line has an ETA
  EXPECT_NE(log.find("ETA"), std::string::npos) << log;
}

TEST_F(DatasetRun, ASampleAfterAnotherOnTheSamePoseIsTheSameAsAlone) {
  // a fixed pose and heart: the renderer keeps the pose's projection and the beating background
  // from one sample to the next. Each sample made alone (a resume at every sample, one per run)
  // must give the bytes it gives after its neighbours
  const std::string spec = write_spec("kept", R"("samples": 3, "frames_per_sample": 2, "seed": 3,
      "warmup_s": {"uniform": [0.5, 1.0]}, "contrast": {"probability": 1.0, "start_s": -0.5},
      "vary": {"effects.detector_noise.photons_per_pixel": {"log_uniform": [500, 3000]}})",
                                      /*beating=*/true);
  std::string log;
  ASSERT_EQ(run("--spec " + spec + " --out " + (dir_ / "together").string(), &log), 0) << log;
  for (int k = 0; k < 3; ++k)
    ASSERT_EQ(run("--spec " + spec + " --out " + (dir_ / "alone").string() + " --max-samples 1", &log), 0) << log;
  EXPECT_EQ(read_json(dir_ / "alone" / "manifest.json")["samples"],
            read_json(dir_ / "together" / "manifest.json")["samples"]);
}

TEST_F(DatasetRun, LabelsLandWhereTheDocumentedProjectionPutsThem) {
  const std::string spec = write_spec("labels", R"("samples": 1, "frames_per_sample": 1, "seed": 2,
      "warmup_s": 3, "driver": {"insert_rate_mm_s": 8, "rotate_rate_deg_s": 0},
      "contrast": {"probability": 1.0, "start_s": -1.5})",
                                      /*beating=*/false, /*noise=*/false);
  std::string log;
  ASSERT_EQ(run("--spec " + spec + " --out " + (dir_ / "d").string(), &log), 0) << log;
  const fs::path s = dir_ / "d" / "samples" / "0000000";
  const auto labels = read_json(s / "frame_0000.json");
  const auto& p = labels["projection"];
  auto vec = [](const nlohmann::json& j) { return Eigen::Vector3d(j[0], j[1], j[2]); };
  const Eigen::Vector3d src = vec(p["source_mm"]), ctr = vec(p["detector_center_mm"]), u = vec(p["u"]), v = vec(p["v"]);
  const double pitch = p["pixel_mm"];
  const int w = p["width"], h = p["height"];
  // the documented formula, written out here: the ray source -> x meets the detector plane, and
  // (c, r) = ((hit - centre).u / pitch + (W-1)/2, (hit - centre).v / pitch + (H-1)/2)
  const Eigen::Vector3d n = u.cross(v).normalized() * (u.cross(v).dot(ctr - src) > 0 ? 1 : -1);
  auto project = [&](const Eigen::Vector3d& x) {
    const Eigen::Vector3d hit = src + (n.dot(ctr - src) / n.dot(x - src)) * (x - src);
    return Eigen::Vector2d((hit - ctr).dot(u) / pitch + 0.5 * (w - 1), (hit - ctr).dot(v) / pitch + 0.5 * (h - 1));
  };
  const auto& nodes = labels["wire"]["nodes_mm"];
  ASSERT_GT(nodes.size(), 10u);
  for (size_t i = 0; i < nodes.size(); ++i) {
    const Eigen::Vector2d cr = project(vec(nodes[i]));
    EXPECT_NEAR(cr.x(), labels["wire"]["nodes_px"][i][0].get<double>(), 2e-3);  // labels keep 1e-3 px
    EXPECT_NEAR(cr.y(), labels["wire"]["nodes_px"][i][1].get<double>(), 2e-3);
  }
  // the frame: the wire's projected polyline lies on darker pixels than the image around it,
  // and the contrast mask on darker pixels than the ring just outside it (noiseless frame)
  std::vector<uint16_t> frame;
  std::vector<uint8_t> mask;
  int fw = 0, fh = 0;
  pcisim::png::read_png_gray16((s / "frame_0000.png").string(), &fw, &fh, &frame);
  pcisim::png::read_png_gray8((s / "mask_0000.png").string(), &fw, &fh, &mask);
  ASSERT_EQ(fw, w);
  ASSERT_EQ(fh, h);
  auto at = [&](int c, int r) { return static_cast<double>(frame[static_cast<size_t>(r) * w + c]); };
  double on = 0, off = 0;
  int count = 0;
  for (const auto& px : labels["wire"]["nodes_px"]) {
    const int c = static_cast<int>(std::lround(px[0].get<double>())),
              r = static_cast<int>(std::lround(px[1].get<double>()));
    if (c < 4 || r < 4 || c >= w - 4 || r >= h - 4) continue;
    if (mask[static_cast<size_t>(r) * w + c]) continue;  // not where the contrast darkens too
    on += at(c, r);
    off += 0.25 * (at(c - 4, r) + at(c + 4, r) + at(c, r - 4) + at(c, r + 4));
    ++count;
  }
  ASSERT_GT(count, 5);
  EXPECT_LT(on / count, off / count - 500) << "the wire's pixels are not darker than their surroundings";
  double in_mask = 0, ring = 0;
  int n_in = 0, n_ring = 0;
  for (int r = 3; r < h - 3; ++r) {
    for (int c = 3; c < w - 3; ++c) {
      const bool m = mask[static_cast<size_t>(r) * w + c] != 0;
      bool near = false;
      for (int d = -3; d <= 3 && !near; ++d)
        near = mask[static_cast<size_t>(r + d) * w + c] || mask[static_cast<size_t>(r) * w + c + d];
      if (m) in_mask += at(c, r), ++n_in;
      if (!m && near) ring += at(c, r), ++n_ring;
    }
  }
  ASSERT_GT(n_in, 50) << "no contrast in the mask";
  EXPECT_LE(n_in, labels["mask_pixels"].get<int>());  // the 3-pixel border left out here
  EXPECT_LT(in_mask / n_in, ring / n_ring - 500) << "the mask is not on the contrast";
}

TEST_F(DatasetRun, AKillMidSampleResumesToTheSameSet) {
  const std::string spec = write_spec("resume", kVaried, /*beating=*/true);
  std::string log;
  ASSERT_EQ(run("--spec " + spec + " --out " + (dir_ / "whole").string(), &log), 0) << log;
  // the same run killed (SIGKILL) while its second sample is being written
  const fs::path out = dir_ / "killed";
  const pid_t pid = fork();
  if (pid == 0) {
    execl(kTool.c_str(), kTool.c_str(), "--spec", spec.c_str(), "--out", out.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  bool killed = false;
  while (std::chrono::steady_clock::now() < deadline && !killed) {
    if (fs::exists(out / "samples" / "0000000") && fs::exists(out / "samples" / ".partial-0000001")) {
      kill(pid, SIGSTOP);  // held mid-sample while a second process tries the same shard
      std::string second;
      EXPECT_EQ(run("--spec " + spec + " --out " + out.string(), &second), 1);
      EXPECT_NE(second.find("another process"), std::string::npos) << second;
      EXPECT_TRUE(fs::exists(out / "samples" / ".partial-0000001")) << "the second process touched the first's sample";
      kill(pid, SIGKILL);
      killed = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(killed) << "the run ended before it could be killed mid-sample";
  EXPECT_FALSE(fs::exists(out / "manifest.json"));
  ASSERT_EQ(run("--spec " + spec + " --out " + out.string(), &log), 0) << log;
  EXPECT_NE(log.find("resuming"), std::string::npos) << log;
  EXPECT_EQ(read_json(out / "manifest.json")["samples"], read_json(dir_ / "whole" / "manifest.json")["samples"]);
  EXPECT_EQ(pcisim::test::file_text(out / "coco.json"), pcisim::test::file_text(dir_ / "whole" / "coco.json"));
  EXPECT_FALSE(fs::exists(out / "samples" / ".partial-0000001"));
  // a second resume has nothing left to do, and another spec is refused in this folder
  ASSERT_EQ(run("--spec " + spec + " --out " + out.string(), &log), 0) << log;
  EXPECT_NE(log.find("3 of 3 samples already made"), std::string::npos) << log;
  const std::string other = write_spec("other", R"("samples": 2)");
  EXPECT_EQ(run("--spec " + other + " --out " + out.string(), &log), 1);
  EXPECT_NE(log.find("another spec"), std::string::npos) << log;
}

TEST_F(DatasetRun, AFailingSampleIsRecordedAndTheRunGoesOn) {
  // each value is fine on its own; the source-to-axis distance drawn above a drawn SID is not
  const std::string spec = write_spec("fail", R"("samples": 6, "frames_per_sample": 1, "seed": 5, "warmup_s": 0.2,
      "vary": {"effects.xray.sid_mm": {"choice": [800, 1100]}, "effects.xray.sad_mm": {"choice": [750, 900]}})");
  std::string log;
  ASSERT_EQ(run("--spec " + spec + " --out " + (dir_ / "f").string(), &log), 0) << log;
  const auto m = read_json(dir_ / "f" / "manifest.json");
  ASSERT_GT(m["failed"].size(), 0u) << "no sample drew the bad combination with this seed";
  EXPECT_EQ(m["samples"].size() + m["failed"].size(), 6u);
  for (const auto& f : m["failed"]) {
    EXPECT_NE(f["error"].get<std::string>().find("sad_mm"), std::string::npos) << f.dump();
    EXPECT_TRUE(f.contains("seed"));
    EXPECT_FALSE(fs::exists(dir_ / "f" / "samples" / fmt::format("{:07d}", f["sample"].get<int64_t>())));
  }
  // the folder was made as one shard: a run in two is refused, naming the count
  EXPECT_EQ(run("--spec " + spec + " --out " + (dir_ / "f").string() + " --shard 1/2", &log), 1);
  EXPECT_NE(log.find("in 1 shards, not 2"), std::string::npos) << log;
}

TEST_F(DatasetRun, AFullDiskIsReportedAndNothingHalfWrittenIsListed) {
  if (geteuid() != 0 || std::system("unshare -m true > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "needs root and mount namespaces (unshare -m) for a small private tmpfs";
  const std::string spec = write_spec("full", R"("samples": 40, "frames_per_sample": 2, "seed": 1, "warmup_s": 0.2)");
  const fs::path out = dir_ / "small";
  fs::create_directories(out);
  // a 1 MiB tmpfs holds a few samples of 128-pixel frames, not forty
  const std::string cmd = "unshare -m sh -c 'mount -t tmpfs -o size=1m tmpfs " + out.string() + " && " + kTool +
                          " --spec " + spec + " --out " + out.string() + "; echo rc=$?; ls -a " + out.string() +
                          "/samples; cat " + out.string() + "/shards/shard-0-of-1.jsonl; for d in " + out.string() +
                          "/samples/0*; do echo digest samples/$(basename $d) $(" + kTool + " --digest $d); done' > " +
                          (dir_ / "full.log").string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const std::string log = pcisim::test::file_text(dir_ / "full.log");
  EXPECT_NE(log.find("rc=4"), std::string::npos) << log;
  EXPECT_NE(log.find("disk is full"), std::string::npos) << log;
  EXPECT_EQ(log.find("\n.partial-"), std::string::npos) << "a partial sample was left (ls):\n" << log;
  // every listed sample is whole: its files' digest, taken inside the private mount before it
  // went away, is the digest its line recorded when it was listed
  std::istringstream lines(log);
  std::string line;
  int listed = 0, checked = 0;
  while (std::getline(lines, line)) {
    if (line.starts_with("{\"anatomy\"")) ++listed;
    if (line.starts_with("digest ")) {
      std::istringstream d(line.substr(7));
      std::string dir, now;
      d >> dir >> now;
      EXPECT_NE(log.find("\"digest\":\"" + now + "\",\"dir\":\"" + dir + "\""), std::string::npos)
          << dir << " is listed with another digest than its files have:\n"
          << log;
      ++checked;
    }
  }
  EXPECT_GT(listed, 0) << log;
  EXPECT_LT(listed, 40) << log;
  EXPECT_EQ(checked, listed) << log;
}

}  // namespace
