// The session runner (server/session_runner.h) with whole pipelines on memq: --case (the
// session's case_dir) applies to every scene, also one loaded over LCM that names another
// anatomy, and to the soft-tissue scene, whose procedural organ it replaces by the case's; a
// refused scene leaves the running one running.
#include "server/session_runner.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/base_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "anatomy/case/case_folder.h"
#include "anatomy/phantom/phantom_case.h"
#include "pcisim_lcm/session_command_t.hpp"
#include "protocol/channels.h"
#include "server/case_builder.h"
#include "server/scene/scene.h"

namespace pcisim::server {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

void load_scene_over_lcm(lcm::LCM& lcm, const std::string& path) {
  pcisim_lcm::session_command_t m{};
  m.command = pcisim_lcm::session_command_t::CMD_LOAD_SCENE;
  m.scene_path = path;
  lcm.publish(protocol::kSessionChannel, &m);
}

// spdlog's lines, readable while the server still writes them
class TextSink : public spdlog::sinks::base_sink<std::mutex> {
 public:
  std::string text() {
    std::lock_guard<std::mutex> lock(mutex_);
    return text_;
  }

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    spdlog::memory_buf_t line;
    formatter_->format(msg, line);
    text_.append(line.data(), line.size());
  }
  void flush_() override {}

 private:
  std::string text_;
};

// the default logger's lines while it lives (the server logs each scene and anatomy it builds)
class CapturedLog {
 public:
  CapturedLog() : previous_(spdlog::default_logger()), sink_(std::make_shared<TextSink>()) {
    spdlog::set_default_logger(std::make_shared<spdlog::logger>("test", sink_));
  }
  ~CapturedLog() { spdlog::set_default_logger(previous_); }
  std::string text() const { return sink_->text(); }
  // waits until a line holds `what` (the server has got that far); false after `timeout`
  bool wait_for(const std::string& what, std::chrono::milliseconds timeout) const {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (text().find(what) == std::string::npos) {
      if (std::chrono::steady_clock::now() > end) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
  }

 private:
  std::shared_ptr<spdlog::logger> previous_;
  std::shared_ptr<TextSink> sink_;
};

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

class SessionRunner : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pcisim-session-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // a small phantom case (coarse CT: quick to write and to read)
    anatomy::PhantomCaseSpec spec;
    spec.ct_dims = {48, 48, 36};
    spec.ct_spacing_mm = 5.0;
    anatomy::write_case(anatomy::make_phantom_case(spec), (dir_ / "patient").string());
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// a scene loaded over LCM naming a case folder that does not exist still runs on --case: it
// used to lose --case, fail to build on its own anatomy and be refused
TEST_F(SessionRunner, TheCaseOptionAppliesToEveryScene) {
  std::ofstream(dir_ / "reloaded.json")
      << R"({"name": "reloaded", "anatomy": {"case": "no-such-case"}, "effects": {"guidewire": {}}})";
  lcm::LCM lcm("memq://");
  SessionLimits limits;
  SessionOptions options;
  options.duration_s = 2.0;
  options.image_url = "memq://";
  options.case_dir = (dir_ / "patient").string();
  std::atomic<bool> stop{false};
  CapturedLog log;
  // memq drops what is published before the server subscribes: send once it runs (under a
  // sanitizer building the first scene can take longer than any fixed wait)
  std::thread console([&] {
    if (log.wait_for("running:", 60s)) load_scene_over_lcm(lcm, (dir_ / "reloaded.json").string());
  });
  StatsReport r;
  EXPECT_NO_THROW(
      r = run_session(load_scene_file(PCISIM_SOURCE_DIR "/scenes/minimal.json"), lcm, options, stop, limits));
  console.join();
  const std::string lines = log.text();
  EXPECT_EQ(count(lines, "scene 'reloaded'"), 1u) << "the scene was not reloaded:\n" << lines;
  EXPECT_EQ(count(lines, "(case " + options.case_dir + ")"), 2u) << "both pipelines on --case:\n" << lines;
  EXPECT_EQ(count(lines, "no-such-case"), 0u) << lines;
  EXPECT_EQ(r.scenes_rejected, 0);
  EXPECT_EQ(r.scene_loads_refused, 0);
  EXPECT_GT(r.physics_steps, 0);
}

// a scene refused while another runs leaves that one running, untouched: it is never rebuilt, so
// even with its case's files gone the session goes on to its end (it used to restart the running
// scene from its files after a refusal, and end with their error once they were gone)
TEST_F(SessionRunner, ARefusedSceneLeavesTheRunningOneRunning) {
  std::ofstream(dir_ / "garbage.motion") << "this is not a heart motion file\n";
  std::ofstream(dir_ / "unbuildable.json") << R"({"effects": {"heart_beat": {"motion_file": "garbage.motion"}}})";
  lcm::LCM lcm("memq://");
  SessionLimits limits;
  SessionOptions options;
  options.duration_s = 3.0;
  options.image_url = "memq://";
  options.case_dir = (dir_ / "patient").string();
  std::atomic<bool> stop{false};
  CapturedLog log;
  std::thread console([&] {
    if (!log.wait_for("running:", 60s)) return;
    fs::remove(dir_ / "patient" / "vessels.json");  // the running scene's case can no longer be read
    load_scene_over_lcm(lcm, (dir_ / "unbuildable.json").string());
  });
  StatsReport r;
  EXPECT_NO_THROW(
      r = run_session(load_scene_file(PCISIM_SOURCE_DIR "/scenes/minimal.json"), lcm, options, stop, limits));
  console.join();
  const std::string lines = log.text();
  EXPECT_EQ(limits.scenes_rejected(), 1);
  EXPECT_EQ(r.scenes_rejected, 1);
  EXPECT_EQ(count(lines, "running:"), 1u) << "one pipeline ran the whole session:\n" << lines;
  EXPECT_EQ(count(lines, "runs on"), 1u) << lines;
  EXPECT_GT(r.elapsed_s, 2.9) << "the running scene went on to the session's end";
  EXPECT_GT(r.physics_steps, 0);
}

// --case with the kidney scene (which names the procedural kidney): the session runs on the
// case's organ; a case without one is refused naming its case.json
TEST_F(SessionRunner, TheCaseOptionGivesTheKidneySceneItsOrgan) {
  std::ofstream(dir_ / "kidney.json") << R"({"name": "kidney-light", "anatomy": {"organ": "kidney"},
    "effects": {"soft_tissue": {"particle_radius_mm": 5}, "probe_contact": {}}})";
  const Scene scene = load_scene_file((dir_ / "kidney.json").string());
  anatomy::write_case(kidney_case(scene), (dir_ / "kidney-case").string());
  lcm::LCM lcm("memq://");
  SessionLimits limits;
  SessionOptions options;
  options.duration_s = 0.5;
  options.image_url = "memq://";
  options.case_dir = (dir_ / "kidney-case").string();
  std::atomic<bool> stop{false};
  {
    CapturedLog log;
    StatsReport r;
    ASSERT_NO_THROW(r = run_session(scene, lcm, options, stop, limits));
    const std::string lines = log.text();
    EXPECT_EQ(count(lines, "(case " + options.case_dir + ")"), 1u) << lines;
    EXPECT_EQ(count(lines, "kidney: "), 1u) << "the tissue was built from the case's organ:\n" << lines;
    EXPECT_GT(r.physics_steps, 0);
  }
  // the coronary case has no organ
  options.case_dir = (dir_ / "patient").string();
  try {
    run_session(scene, lcm, options, stop, limits);
    ADD_FAILURE() << "the kidney scene ran on a case without an organ";
  } catch (const anatomy::CaseError& e) {
    EXPECT_NE(std::string(e.what()).find((dir_ / "patient" / "case.json").string() + ": organ: missing"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace pcisim::server
