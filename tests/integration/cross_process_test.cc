// Server and bridge as separate processes over udpm (ttl=0) inside a private network namespace,
// so nothing leaves this host. Skips where namespaces are not permitted.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <sys/wait.h>

namespace {

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(CrossProcess, BridgeAndServerTalkOverUdpmInAPrivateNamespace) {
  if (std::system("unshare -n true 2>/dev/null") != 0)
    GTEST_SKIP() << "network namespaces are not permitted here (needs root or user namespaces); "
                    "the cross-process test cannot run without one";
  const auto dir = std::filesystem::temp_directory_path() / "pcisim_cross_process";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string url = "'udpm://239.255.76.67:7667?ttl=0'";
  const std::string bin = PCISIM_BINARY_DIR;
  const std::string cmd =
      std::string(PCISIM_SOURCE_DIR) + "/scripts/in-private-netns bash -c \"" + bin +
      "/server/pcisim-server --duration 3 --scene " PCISIM_SOURCE_DIR "/scenes/minimal.json --lcm-url " + url +
      " --stats-json " + (dir / "stats.json").string() + " > " + (dir / "server.log").string() + " 2>&1 & " + bin +
      "/clients/pcisim-bridge --duration 2 --wait-for-server 20 --lcm-url " + url + " > " +
      (dir / "bridge.log").string() + " 2>&1; wait\"";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  if (WEXITSTATUS(status) == 77) GTEST_SKIP() << "in-private-netns could not create a namespace";
  ASSERT_EQ(WEXITSTATUS(status), 0) << slurp(dir / "server.log") << slurp(dir / "bridge.log");

  const auto stats = nlohmann::json::parse(slurp(dir / "stats.json"));
  EXPECT_GT(stats["lcm"]["rx"].get<int64_t>(), 1500) << "instrument samples crossed processes";
  EXPECT_EQ(stats["lcm"]["dropped_bad"].get<int64_t>(), 0);

  std::smatch m;
  const std::string bridge_log = slurp(dir / "bridge.log");
  ASSERT_TRUE(std::regex_search(bridge_log, m, std::regex("(\\d+) force commands received, (\\d+) bad"))) << bridge_log;
  EXPECT_GT(std::stoll(m[1]), 1500) << "force commands came back at about 1 kHz";
  EXPECT_EQ(std::stoll(m[2]), 0);
}

}  // namespace
