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
  EXPECT_NE(r.output.find("--profile describes an instrument box: it needs --device serial"), std::string::npos)
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
