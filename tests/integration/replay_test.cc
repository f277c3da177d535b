// A session recorded with lcm-logger and replayed through pcisim-bridge --device replay drives
// the server along the same wire trajectory as the live session. Separate processes over udpm
// inside a private network namespace; skips where namespaces are not permitted.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>

#include "pcisim_lcm/wire_state_t.hpp"
#include "protocol/channels.h"
#include "realtime/percentile.h"
#include "server/scene/scene.h"

#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;

std::vector<pcisim_lcm::wire_state_t> wire_states(const std::string& path) {
  std::vector<pcisim_lcm::wire_state_t> out;
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != pcisim::protocol::kWireChannel) continue;
    pcisim_lcm::wire_state_t m;
    if (m.decode(e->data, 0, e->datalen) == e->datalen) out.push_back(m);
  }
  return out;
}

// runs the server, a bridge and a logger in a private namespace; returns the shell's status.
// The body is double-quoted for the outer shell, so the inner shell's $ are escaped.
int session(const fs::path& dir, const std::string& bridge_args, const std::string& log_name) {
  // a scene without the time-driven effects: with the heart beating, the world path also depends
  // on which phase the recording met, which the replay (starting on its own clock) cannot reproduce
  const std::string scene = " --scene " + (dir / "still.json").string();
  const std::string url = "'udpm://239.255.76.67:7667?ttl=0'";
  const std::string bin = PCISIM_BINARY_DIR;
  const std::string body = "lcm-logger --quiet --lcm-url " + url + " " + (dir / log_name).string() + " & L=\\$!; " +
                           bin + "/server/pcisim-server --duration 9 --lcm-url " + url + scene +
                           " --log-level warn & S=\\$!; " + bin +
                           "/clients/pcisim-bridge --wait-for-server 30 --lcm-url " + url + " " + bridge_args + " > " +
                           (dir / (log_name + ".bridge.txt")).string() +
                           " 2>&1; kill -TERM \\$S; wait \\$S; sleep 0.3; kill -TERM \\$L; wait \\$L; true";
  const std::string cmd = std::string(PCISIM_SOURCE_DIR) + "/scripts/in-private-netns bash -c \"" + body + "\"";
  return std::system(cmd.c_str());
}

TEST(Replay, ReplayedSessionFollowsTheLiveWireTrajectory) {
  if (std::system("unshare -n true 2>/dev/null") != 0) GTEST_SKIP() << "network namespaces are not permitted here";
  const fs::path dir = fs::temp_directory_path() / "pcisim_replay";
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    // the built-in scene without heart_beat, vessel_motion and blood_flow: the blood chain-mails
    // flow past the wire, so the drift they give depends on when a step samples them, which a
    // replay on its own clock cannot reproduce either
    auto scene = nlohmann::json::parse(pcisim::server::default_scene_text(), nullptr, true, /*ignore_comments=*/true);
    scene["effects"].erase("heart_beat");
    scene["effects"].erase("vessel_motion");
    scene["effects"].erase("blood_flow");
    std::ofstream(dir / "still.json") << scene.dump(2);
  }
  std::ofstream(dir / "script.json") << R"({"name": "short", "actions": [
      {"at_s": 0.2, "do": "insert", "mm": 15, "over_s": 3},
      {"at_s": 1.5, "do": "rotate", "deg": 120, "over_s": 2},
      {"at_s": 3.5, "do": "insert", "mm": 10, "over_s": 1.5}]})";
  ASSERT_EQ(session(dir, "--device scripted --duration 5.5 --script " + (dir / "script.json").string(), "live.lcmlog"),
            0);
  ASSERT_EQ(session(dir, "--device replay --log " + (dir / "live.lcmlog").string(), "replay.lcmlog"), 0);

  const auto live = wire_states((dir / "live.lcmlog").string());
  const auto replay = wire_states((dir / "replay.lcmlog").string());
  ASSERT_GT(live.size(), 100u);
  ASSERT_GT(replay.size(), 100u);
  // the replay's tip must trace the live tip's path: every replayed tip position lies near the
  // live path (a polyline through the live tips), and both end in the same place. Physics steps
  // see the samples at another phase of the 30 Hz clock, and wall contact can make the tip jump
  // a millimetre or two in one step, so the stated tolerance is 0.3 mm typical (median), 1 mm
  // for 95 % of the states, 4 mm worst, 1 mm at the end (seen: worst 0.15-1.24 mm on a quiet
  // machine, 2.64 mm with the suite run two at a time beside a busy loop: late steps see the
  // samples further apart, and the single worst state is the one a loaded machine moves)
  constexpr double kMedianMm = 0.3, kP95Mm = 1.0, kWorstMm = 4.0, kEndMm = 1.0;
  auto tip = [](const pcisim_lcm::wire_state_t& w) { return Eigen::Vector3d(w.tip_mm[0], w.tip_mm[1], w.tip_mm[2]); };
  auto distance_to_live_path = [&](const Eigen::Vector3d& p) {
    double best = 1e9;
    for (size_t i = 1; i < live.size(); ++i) {
      const Eigen::Vector3d a = tip(live[i - 1]), b = tip(live[i]);
      const double len2 = (b - a).squaredNorm();
      const double u = len2 > 0 ? std::clamp((p - a).dot(b - a) / len2, 0.0, 1.0) : 0.0;
      best = std::min(best, (a + u * (b - a) - p).norm());
    }
    return best;
  };
  std::vector<double> d;
  for (const auto& r : replay) d.push_back(distance_to_live_path(tip(r)));
  const double median = pcisim::realtime::percentile(d, 0.5), p95 = pcisim::realtime::percentile(d, 0.95);
  const double worst = pcisim::realtime::percentile(d, 1.0);
  EXPECT_LT(median, kMedianMm) << "replayed tip positions against the live tip path";
  EXPECT_LT(p95, kP95Mm) << "replayed tip positions against the live tip path";
  EXPECT_LT(worst, kWorstMm) << "replayed tip positions against the live tip path";
  EXPECT_LT((tip(live.back()) - tip(replay.back())).norm(), kEndMm) << "both sessions end in the same place";
  std::printf("replay: tip distance to the live path median %.3f mm, p95 %.3f mm, worst %.3f mm\n", median, p95, worst);
  const double travelled = (tip(live.back()) - tip(live.front())).norm();
  EXPECT_GT(travelled, 15.0) << "the session moved the wire";
  RecordProperty("worst_tip_difference_mm", std::to_string(worst));
}

}  // namespace
