// pcisim-server as a person runs it: --help, --write-scene, bad scenes, --stats-json.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

namespace {

struct Result {
  int exit_code;
  std::string output;
};

Result run(const std::string& args) {
  const std::string cmd = std::string(PCISIM_BINARY_DIR) + "/server/pcisim-server " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  while (size_t n = fread(buf.data(), 1, buf.size(), pipe)) out.append(buf.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

const std::filesystem::path kDir = std::filesystem::temp_directory_path() / "pcisim_server_cli";

TEST(ServerCli, HelpExplainsTheOptions) {
  const Result r = run("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* option : {"--scene", "--duration", "--lcm-url", "--stats-json", "--log-level", "--write-scene"})
    EXPECT_NE(r.output.find(option), std::string::npos) << option;
}

TEST(ServerCli, WriteSceneWritesTheBuiltInScene) {
  std::filesystem::create_directories(kDir);
  const auto path = kDir / "scene.json";
  const Result r = run("--write-scene " + path.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(slurp(path), slurp(PCISIM_SOURCE_DIR "/scenes/default.json"));
}

TEST(ServerCli, BadSceneStopsAtStartWithTheJsonPath) {
  std::filesystem::create_directories(kDir);
  const auto path = kDir / "bad.json";
  std::ofstream(path) << R"({"effects": {"guidewire": {"segments": 1}}})";
  const Result r = run("--duration 1 --lcm-url memq:// --scene " + path.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("bad scene: " + path.string() +
                          ": effects.guidewire.segments: expected an integer in [4, 4000], got 1"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("running"), std::string::npos) << "never starts half a scene";

  const Result missing = run("--duration 1 --lcm-url memq:// --scene /nonexistent.json");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("/nonexistent.json: cannot open the scene file"), std::string::npos) << missing.output;
}

TEST(ServerCli, RunsForItsDurationAndWritesStats) {
  std::filesystem::create_directories(kDir);
  const auto stats = kDir / "stats.json";
  std::filesystem::remove(stats);
  const Result r = run("--duration 1.5 --lcm-url memq:// --log-level warn --stats-json " + stats.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("haptic"), std::string::npos) << "a human summary at exit";
  const auto j = nlohmann::json::parse(slurp(stats));
  // rates: the loops ran (how steadily a shared machine lets them is the benchmarks' business)
  EXPECT_GT(j["haptic"]["rate_hz"].get<double>(), 500.0);
  EXPECT_GT(j["physics"]["rate_hz"].get<double>(), 15.0);
  EXPECT_EQ(j["physics"]["effects"].size(), 6u);  // heart_beat, vessel_motion, guidewire, blood, contact, friction
}

TEST(ServerCli, SigtermStopsCleanlyAndStillWritesStats) {
  std::filesystem::create_directories(kDir);
  const auto stats = kDir / "stats_sigterm.json";
  std::filesystem::remove(stats);
  const std::string cmd = std::string(PCISIM_BINARY_DIR) +
                          "/server/pcisim-server --scene " PCISIM_SOURCE_DIR
                          "/scenes/minimal.json --lcm-url memq:// --log-level warn --stats-json " +
                          stats.string() + " > /dev/null 2>&1 & pid=$!; sleep 1.5; kill -TERM $pid; wait $pid";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "SIGTERM is a normal way to stop";
  ASSERT_TRUE(std::filesystem::exists(stats));
  EXPECT_GT(nlohmann::json::parse(slurp(stats))["haptic"]["ticks"].get<int64_t>(), 500);
}

}  // namespace
