// SIGTERM during a long start of the real programs ends them within a second, with a non-zero
// exit and one line naming the signal (realtime/stop_signal.h); it once waited for the start to
// finish (pcisim-server: 4 s building the built-in scene) or killed without a word (pcisim-model).
#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/common/run_program.h"

namespace {

namespace fs = std::filesystem;

const std::string kBin = PCISIM_BINARY_DIR;

// runs argv, sends SIGTERM after term_after_s (once its handler is in place)
pcisim::test::ProgramRun term_during_start(const std::vector<std::string>& argv, double term_after_s) {
  return pcisim::test::run_program(argv, term_after_s, /*limit_s=*/40);
}

TEST(StopSignals, TheServerAnswersSigtermWhileBuildingItsScene) {
  // the built-in scene's phantom, contact field and CT take seconds to build
  const pcisim::test::ProgramRun s =
      term_during_start({kBin + "/server/pcisim-server", "--lcm-url", "memq://", "--duration", "20"}, 0.4);
  ASSERT_GE(s.after_term_s, 0) << "it ended before the signal: " << s.output;
  EXPECT_TRUE(s.exited) << "killed by signal " << s.code << "\n" << s.output;
  EXPECT_EQ(s.code, 128 + SIGTERM) << s.output;
  EXPECT_LT(s.after_term_s, 1.0) << s.output;
  EXPECT_NE(s.output.find("pcisim-server: stopped by SIGTERM"), std::string::npos) << s.output;
}

TEST(StopSignals, TheModelToolAnswersSigtermWhileMakingAPhantom) {
  const std::string model = kBin + "/modeling/pcisim-model";
  if (!fs::exists(model)) GTEST_SKIP() << "pcisim-model is not built (no ITK)";
  const fs::path out = fs::temp_directory_path() / ("pcisim-stop-signals-" + std::to_string(::getpid()));
  // the default phantom CTA (512 x 512 x 250) takes seconds
  const pcisim::test::ProgramRun s =
      term_during_start({model, "--make-phantom-cta", "--seed", "1", "--out", out.string()}, 0.4);
  fs::remove_all(out);
  ASSERT_GE(s.after_term_s, 0) << "it ended before the signal: " << s.output;
  EXPECT_TRUE(s.exited) << "killed by signal " << s.code << " without a word\n" << s.output;
  EXPECT_EQ(s.code, 128 + SIGTERM) << s.output;
  EXPECT_LT(s.after_term_s, 1.0) << s.output;
  EXPECT_NE(s.output.find("pcisim-model: stopped by SIGTERM while working"), std::string::npos) << s.output;
}

}  // namespace
