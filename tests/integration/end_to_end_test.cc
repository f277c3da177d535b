// The cath-lab shape: pcisim-server, pcisim-bridge (scripted trainee) and pcisim-capture as
// separate processes over udpm (ttl=0) inside a private network namespace. Frames with correct
// sidecars must appear, and force commands must come back to the bridge.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Dense>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <sys/wait.h>

#include "tests/common/file_text.h"

namespace {

namespace fs = std::filesystem;

using pcisim::test::file_text;

TEST(EndToEnd, ServerBridgeAndCaptureProduceLabelledFramesAndForces) {
  if (std::system("unshare -n true 2>/dev/null") != 0) GTEST_SKIP() << "network namespaces are not permitted here";
  const fs::path dir = fs::temp_directory_path() / "pcisim_end_to_end";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "scene.json") << R"({"name": "e2e", "effects": {
      "guidewire": {}, "vessel_contact": {}, "friction": {},
      "xray": {"detector_px": 160, "pixel_mm": 1.28, "volume_voxels": 128, "volume_spacing_mm": 2.8},
      "contrast": {}, "detector_noise": {}}})";
  std::ofstream(dir / "script.json") << R"({"name": "e2e", "actions": [
      {"at_s": 0.2, "do": "insert", "mm": 8, "over_s": 1.5},
      {"at_s": 0.5, "do": "pedal", "down": true},
      {"at_s": 1.0, "do": "contrast", "for_s": 1},
      {"at_s": 1.8, "do": "rotate", "deg": 90, "over_s": 1},
      {"at_s": 2.8, "do": "insert", "mm": 15, "over_s": 1.5},
      {"at_s": 4.5, "do": "pedal", "down": false}]})";
  const std::string url = "'udpm://239.255.76.67:7667?ttl=0'",
                    images = "'udpm://239.255.76.67:7668?ttl=0&recv_buf_size=4194304'";
  const std::string bin = PCISIM_BINARY_DIR, d = dir.string();
  const std::string body = bin + "/clients/pcisim-capture --out " + d + "/frames --lcm-image-url " + images + " > " +
                           d + "/capture.txt 2>&1 & C=\\$!; " + bin + "/server/pcisim-server --duration 8 --scene " +
                           d + "/scene.json --lcm-url " + url + " --lcm-image-url " + images + " --stats-json " + d +
                           "/stats.json > " + d + "/server.txt 2>&1 & S=\\$!; " + bin +
                           "/clients/pcisim-bridge --duration 5 --wait-for-server 60 --script " + d +
                           "/script.json --lcm-url " + url + " > " + d +
                           "/bridge.txt 2>&1; B=\\$?; kill -TERM \\$S; wait \\$S; R=\\$?; sleep 0.3; kill -TERM \\$C; "
                           "wait \\$C; exit \\$((B + R))";
  const int status =
      std::system((std::string(PCISIM_SOURCE_DIR) + "/scripts/in-private-netns bash -c \"" + body + "\"").c_str());
  ASSERT_TRUE(WIFEXITED(status));
  if (WEXITSTATUS(status) == 77) GTEST_SKIP() << "in-private-netns could not create a namespace";
  ASSERT_EQ(WEXITSTATUS(status), 0) << file_text(dir / "server.txt") << file_text(dir / "bridge.txt");

  // forces came back to the bridge
  std::smatch m;
  const std::string bridge = file_text(dir / "bridge.txt");
  ASSERT_TRUE(std::regex_search(bridge, m, std::regex("(\\d+) force commands received, (\\d+) bad"))) << bridge;
  EXPECT_GT(std::stoll(m[1]), 3000);

  // frames with sidecars appeared while the pedal was down, and their labels are exact
  std::vector<fs::path> sidecars;
  for (const auto& e : fs::directory_iterator(dir / "frames" / "fluoro"))
    if (e.path().extension() == ".json") sidecars.push_back(e.path());
  ASSERT_GT(sidecars.size(), 30u) << file_text(dir / "capture.txt");
  int with_contrast = 0;
  for (const auto& path : sidecars) {
    EXPECT_TRUE(fs::exists(fs::path(path).replace_extension(".png"))) << path;
    const auto j = nlohmann::json::parse(file_text(path));
    const auto& det = j["detector"];
    auto vec = [](const nlohmann::json& a) {
      return Eigen::Vector3d(a[0].get<double>(), a[1].get<double>(), a[2].get<double>());
    };
    const Eigen::Vector3d s = vec(det["source_mm"]), c = vec(det["center_mm"]), u = vec(det["u"]), v = vec(det["v"]);
    const double pitch = det["pixel_mm"].get<double>();
    const int w = det["width"].get<int>(), h = det["height"].get<int>();
    const Eigen::Vector3d n = u.cross(v).normalized();
    const auto& wire_mm = j["labels"]["wire_mm"];
    const auto& wire_px = j["labels"]["wire_px"];
    ASSERT_EQ(wire_mm.size(), wire_px.size());
    ASSERT_GT(wire_mm.size(), 10u);
    double worst = 0;
    for (size_t i = 0; i < wire_mm.size(); ++i) {
      const Eigen::Vector3d p = vec(wire_mm[i]);
      const Eigen::Vector3d hit = s + ((c - s).dot(n) / (p - s).dot(n)) * (p - s);
      const double col = (hit - c).dot(u) / pitch + 0.5 * (w - 1), row = (hit - c).dot(v) / pitch + 0.5 * (h - 1);
      worst =
          std::max({worst, std::abs(col - wire_px[i][0].get<double>()), std::abs(row - wire_px[i][1].get<double>())});
    }
    EXPECT_LT(worst, 0.5) << "re-projection error of " << path;
    with_contrast += !j["labels"]["contrast_branches"].empty();
  }
  EXPECT_GT(with_contrast, 5) << "the injection shows in the labels";
  const auto stats = nlohmann::json::parse(file_text(dir / "stats.json"));
  EXPECT_EQ(stats["xray"]["frames"].get<int64_t>(), static_cast<int64_t>(sidecars.size())) << "every frame captured";
}

}  // namespace
