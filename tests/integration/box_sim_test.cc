// The instrument box programs together, as scripts/main-job runs them: pcisim-box-sim on a
// pseudo-terminal and pcisim-bridge --device serial on its link. With no server answering, the
// bridge reads the box's encoder lines and sends nothing but zero force (its closing figures and
// the box's log say so); the programs refuse bad profiles and links naming them.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <sys/wait.h>
#include <cstdio>
#include <cstdlib>

#include "tests/common/run_program.h"

namespace pcisim {
namespace {

namespace fs = std::filesystem;
const std::string kBin = PCISIM_BINARY_DIR;

struct TempDir {
  fs::path path;
  TempDir() {
    char tmpl[] = "/tmp/pcisim_box_sim_XXXXXX";
    path = ::mkdtemp(tmpl);
  }
  ~TempDir() { fs::remove_all(path); }
};

std::string file_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(BoxSimProgram, TheBridgeReadsTheBoxAndSendsZeroForceWithoutAServer) {
  TempDir dir;
  const std::string link = dir.path / "box.pty", log = dir.path / "forces.csv", stats = dir.path / "bridge.json";
  // the box runs 3 s; the bridge starts once the link is there and runs 1 s on memq (no server)
  test::ProgramRun box_run;
  std::thread box([&] {
    box_run = test::run_program({kBin + "/clients/pcisim-box-sim", "--link", link, "--duration", "3", "--log", log});
  });
  for (int i = 0; i < 300 && !fs::is_symlink(link); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(fs::is_symlink(link)) << "the box made no link";
  const test::ProgramRun bridge =
      test::run_program({kBin + "/clients/pcisim-bridge", "--device", "serial", "--port", link, "--duration", "1",
                         "--lcm-url", "memq://", "--stats-json", stats});
  box.join();
  EXPECT_TRUE(bridge.exited && bridge.code == 0) << bridge.output;
  EXPECT_TRUE(box_run.exited && box_run.code == 0) << box_run.output;
  EXPECT_FALSE(fs::exists(link)) << "the box removes its link when it ends";
  // the bridge read the box, and every tick's force was zero: no server
  const std::string s = file_text(stats);
  EXPECT_NE(s.find("\"force_lines_dropped\": 0"), std::string::npos) << s;
  EXPECT_NE(bridge.output.find("serial lines"), std::string::npos) << bridge.output;
  EXPECT_NE(bridge.output.find("no force command yet"), std::string::npos) << bridge.output;
  // the box's log: force lines, all zero
  std::istringstream csv(file_text(log));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "t_s,axial_mN,torque_uNm,seq");
  int lines = 0;
  while (std::getline(csv, line)) {
    ++lines;
    ASSERT_NE(line.find(",0,0,"), std::string::npos) << line;
  }
  EXPECT_GT(lines, 500) << "about one a millisecond for a second";
  EXPECT_NE(box_run.output.find("force lines applied (0 malformed)"), std::string::npos) << box_run.output;
}

// the server killed (SIGKILL: no goodbye) while the trainee pushes the wire through the default
// scene's vessels: the force lines the box applies turn to zero within 50 ms of the kill, and
// stay zero. Server, bridge and box as separate processes over udpm in a private namespace
TEST(BoxSimProgram, ServerKilledMidPushIsZeroForceAtTheBoxWithin50Ms) {
  if (std::system("unshare -n true 2>/dev/null") != 0)
    GTEST_SKIP() << "network namespaces are not permitted here: the server, bridge and box cannot talk over udpm";
  TempDir dir;
  const fs::path d = dir.path;
  std::ofstream(d / "push.json")
      << R"({"name": "push", "actions": [{"at_s": 0.2, "do": "insert", "mm": 250, "over_s": 8}]})";
  const std::string url = "'udpm://239.255.76.67:7667?ttl=0'";
  // the box holds its script until the first force line; the server dies 3 s after that
  std::ofstream(d / "run.sh") << "set -u\n"
                              << fs::path(kBin + "/clients/pcisim-box-sim") << " --link " << d / "box.pty"
                              << " --duration 8 --hold-until-force --script " << d / "push.json"
                              << " --log " << d / "box.csv"
                              << " > " << d / "box.log"
                              << " 2>&1 &\nbox=$!\n"
                              << fs::path(kBin + "/server/pcisim-server") << " --scene "
                              << fs::path(PCISIM_SOURCE_DIR "/scenes/default.json") << " --duration 60 --lcm-url "
                              << url << " > " << d / "server.log"
                              << " 2>&1 &\nserver=$!\n"
                              << "for i in $(seq 200); do [ -L " << d / "box.pty"
                              << " ] && break; sleep 0.05; done\n"
                              << fs::path(kBin + "/clients/pcisim-bridge") << " --device serial --port "
                              << d / "box.pty"
                              << " --wait-for-server 30 --duration 7.5 --lcm-url " << url << " > " << d / "bridge.log"
                              << " 2>&1 &\nbridge=$!\n"
                              << "for i in $(seq 600); do grep -q 'force commands\\|rendering' " << d / "bridge.log"
                              << " && break; sleep 0.05; done\nsleep 3\n"
                              << "python3 -c \"import os, signal, time; t = time.monotonic_ns(); os.kill($server, "
                                 "signal.SIGKILL); print(t)\" > "
                              << d / "kill_ns"
                              << "\nwait $bridge; wait $box; { wait $server; } 2> /dev/null; exit 0\n";
  const std::string cmd = std::string(PCISIM_SOURCE_DIR) + "/scripts/in-private-netns bash " + (d / "run.sh").string();
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  if (WEXITSTATUS(status) == 77) GTEST_SKIP() << "in-private-netns could not create a namespace";
  const std::string logs = file_text(d / "box.log") + file_text(d / "bridge.log") + file_text(d / "server.log");
  ASSERT_EQ(WEXITSTATUS(status), 0) << logs;
  // the kill on the box's script clock
  const std::string box_log = file_text(d / "box.log");
  const auto at = box_log.find("t=0 at CLOCK_MONOTONIC ");
  ASSERT_NE(at, std::string::npos) << logs;
  const double script_t0_s = std::stod(box_log.substr(at + 23));
  const double kill_s = std::stoll(file_text(d / "kill_ns")) * 1e-9 - script_t0_s;
  // the box's force lines: while the wire moves the server's force is rarely zero; after the kill
  // the bridge's gate zeroes it once the server has been silent 20 ms
  std::istringstream csv(file_text(d / "box.csv"));
  std::string line;
  std::getline(csv, line);
  int before = 0, nonzero_before = 0;
  double last_nonzero_s = -1, last_s = 0;
  while (std::getline(csv, line)) {
    double t = 0;
    long long axial = 0, torque = 0, seq = 0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lld,%lld,%lld", &t, &axial, &torque, &seq), 4) << line;
    last_s = t;
    if (t >= kill_s - 0.2 && t < kill_s) {
      ++before;
      nonzero_before += axial != 0 ? 1 : 0;
    }
    if (axial != 0 || torque != 0) last_nonzero_s = t;
  }
  std::printf(
      "killed at %.3f s of the script; the last non-zero force %.1f ms after; %d of %d lines in the 200 ms "
      "before were non-zero\n",
      kill_s, 1e3 * (last_nonzero_s - kill_s), nonzero_before, before);
  ASSERT_GT(before, 150) << "the box got a line a millisecond before the kill\n" << logs;
  EXPECT_GT(nonzero_before, before / 2) << "the server's force was flowing before the kill\n" << logs;
  EXPECT_GT(last_s, kill_s + 0.5) << "the box ran on after the kill\n" << logs;
  EXPECT_LT(last_nonzero_s - kill_s, 0.050) << "zero force within 50 ms of the kill, and zero after\n" << logs;
}

TEST(BoxSimProgram, BadProfilesAndLinksAreRefusedByName) {
  TempDir dir;
  const std::string profile = dir.path / "box.json";
  std::ofstream(profile) << R"({"force": {"max_axial_n": 50}})";
  test::ProgramRun r = test::run_program({kBin + "/clients/pcisim-bridge", "--device", "serial", "--port", "/dev/null",
                                          "--profile", profile, "--lcm-url", "memq://"});
  EXPECT_TRUE(r.exited && r.code == 2) << r.output;
  EXPECT_NE(r.output.find("box.json: force.max_axial_n: expected a number in [0.001, 20], got 50"), std::string::npos)
      << r.output;
  r = test::run_program({kBin + "/clients/pcisim-bridge", "--device", "scripted", "--profile", profile});
  EXPECT_TRUE(r.exited && r.code == 2) << r.output;
  EXPECT_NE(r.output.find("--profile describes an instrument: it needs --device serial or evdev"), std::string::npos)
      << r.output;
  // a link over a regular file is refused, and the file is left as it was
  const std::string taken = dir.path / "taken";
  std::ofstream(taken) << "keep me";
  r = test::run_program({kBin + "/clients/pcisim-box-sim", "--link", taken, "--duration", "1"});
  EXPECT_TRUE(r.exited && r.code == 2) << r.output;
  EXPECT_NE(r.output.find("exists and is not a symbolic link; not replaced"), std::string::npos) << r.output;
  EXPECT_EQ(file_text(taken), "keep me");
}

}  // namespace
}  // namespace pcisim
