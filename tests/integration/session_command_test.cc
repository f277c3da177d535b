// Session commands over a real in-process LCM: pause/resume, reset and scene loading.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <mutex>
#include <thread>

#include "pcisim_lcm/force_command_t.hpp"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/session_command_t.hpp"
#include "pcisim_lcm/wire_state_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/clock.h"
#include "server/server.h"
#include "server/session_runner.h"

namespace pcisim::server {
namespace {

using C = pcisim_lcm::session_command_t;
using F = pcisim_lcm::force_command_t;

struct Timed {
  double t_s;
  int32_t flags;
  double sim_time_s;
  int64_t seq = 0;
};

// records when wire states and force commands arrive, relative to the test's start
struct Recorder {
  int64_t start_ns = realtime::monotonic_ns();
  std::mutex mutex;
  std::vector<Timed> wires, forces;
  double now_s() const { return (realtime::monotonic_ns() - start_ns) * 1e-9; }
  void on_wire(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::wire_state_t m;
    if (!protocol::decode_checked(*r, m)) return;
    std::lock_guard lock(mutex);
    wires.push_back({now_s(), 0, m.sim_time_s});
  }
  void on_force(const lcm::ReceiveBuffer* r, const std::string&) {
    F m;
    if (!protocol::decode_checked(*r, m)) return;
    std::lock_guard lock(mutex);
    forces.push_back({now_s(), m.flags, 0, m.seq});
  }
};

void send(lcm::LCM& lcm, int8_t command, const std::string& scene_path = "") {
  C c{};
  c.command = command;
  c.scene_path = scene_path;
  lcm.publish(protocol::kSessionChannel, &c);
}

// publishes a steady instrument at 1 kHz until destroyed
struct Instrument {
  lcm::LCM& lcm;
  std::atomic<bool> done{false};
  std::thread thread{[this] {
    pcisim_lcm::instrument_state_t m{};
    for (int64_t seq = 0; !done; ++seq) {
      m.seq = seq;
      lcm.publish(protocol::kInstrumentChannel, &m);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }};
  explicit Instrument(lcm::LCM& l) : lcm(l) {}
  ~Instrument() {
    done = true;
    thread.join();
  }
};

// the default scene's test rig: memq, a recorder of wire states and force commands, and a 1 kHz
// instrument
struct DefaultSceneOverMemq {
  lcm::LCM lcm{"memq://"};
  Recorder rec;
  Instrument instrument{lcm};
  Scene scene = load_scene_file(PCISIM_SOURCE_DIR "/scenes/default.json");
  double period_s = 1.0 / scene.physics_rate_hz;
  DefaultSceneOverMemq() {
    lcm.subscribe(protocol::kWireChannel, &Recorder::on_wire, &rec);
    lcm.subscribe(protocol::kForceChannel, &Recorder::on_force, &rec);
  }
};

Scene minimal() {
  return load_scene_file(PCISIM_SOURCE_DIR "/scenes/minimal.json");
}

TEST(SessionCommands, PauseFreezesPhysicsAndFadesTheForceResumeBringsBothBack) {
  lcm::LCM lcm("memq://");
  Recorder rec;
  lcm.subscribe(protocol::kWireChannel, &Recorder::on_wire, &rec);
  lcm.subscribe(protocol::kForceChannel, &Recorder::on_force, &rec);
  Instrument instrument(lcm);
  Server server(minimal(), lcm);
  std::thread console([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(800));
    send(lcm, C::CMD_PAUSE);
    std::this_thread::sleep_for(std::chrono::milliseconds(1000));
    send(lcm, C::CMD_RESUME);
  });
  std::atomic<bool> stop{false};
  server.run(3.0, stop);
  console.join();

  std::lock_guard lock(rec.mutex);
  double longest_gap = 0;
  for (size_t i = 1; i < rec.wires.size(); ++i)
    longest_gap = std::max(longest_gap, rec.wires[i].t_s - rec.wires[i - 1].t_s);
  EXPECT_GT(longest_gap, 0.8) << "no physics step while paused";
  int stale_while_paused = 0, paused_samples = 0, stale_after = 0, after_samples = 0;
  for (const auto& f : rec.forces) {
    if (f.t_s > 1.2 && f.t_s < 1.7) {
      ++paused_samples;
      stale_while_paused += (f.flags & F::FLAG_STALE) != 0;
    }
    if (f.t_s > 2.6 && f.t_s < 2.9) {
      ++after_samples;
      stale_after += (f.flags & F::FLAG_STALE) != 0;
    }
  }
  ASSERT_GT(paused_samples, 300);
  EXPECT_EQ(stale_while_paused, paused_samples);
  ASSERT_GT(after_samples, 200);
  EXPECT_EQ(stale_after, 0);
}

TEST(SessionCommands, ResetRestartsTheWorld) {
  lcm::LCM lcm("memq://");
  Recorder rec;
  lcm.subscribe(protocol::kWireChannel, &Recorder::on_wire, &rec);
  Instrument instrument(lcm);
  Server server(minimal(), lcm);
  std::thread console([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(1000));
    send(lcm, C::CMD_RESET);
  });
  std::atomic<bool> stop{false};
  server.run(1.6, stop);
  console.join();
  std::lock_guard lock(rec.mutex);
  ASSERT_GT(rec.wires.size(), 30u);
  bool went_back = false;
  for (size_t i = 1; i < rec.wires.size(); ++i) went_back |= rec.wires[i].sim_time_s < rec.wires[i - 1].sim_time_s;
  EXPECT_TRUE(went_back) << "simulated time starts again after a reset";
}

// a reset of the default scene (contact field, beating heart): the world is built again on a
// builder thread while the running one steps on, then swapped in (issue #36; before, physics
// stopped for the whole build, 0.7-1.6 s, and the force went stale for as long). The wire states
// keep coming at the physics rate through the reset and the force never goes stale for long.
// The bound is three physics periods, not zero: on a shared 2-core VM a 3 ms step now and then
// takes 25-40 ms of wall time with or without a reset (a plain 11 ms loop measured up to 72 ms
// there), and one overrun leaves the model (valid two periods) stale for a few ms
TEST(SessionCommands, ResetOfTheDefaultSceneKeepsPhysicsSteppingAndTheForceFresh) {
  DefaultSceneOverMemq rig;
  auto& [lcm, rec, instrument, scene, period_s] = rig;
  Server server(scene, lcm);
  double reset_at_s = 0;
  std::thread console([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(1000));
    reset_at_s = rec.now_s();
    send(lcm, C::CMD_RESET);
  });
  const double run_start_s = rec.now_s();
  std::atomic<bool> stop{false};
  server.run(3.0, stop);
  console.join();
  std::lock_guard lock(rec.mutex);
  ASSERT_GT(reset_at_s, run_start_s);
  double longest_gap = 0, swapped_at_s = -1;
  for (size_t i = 1; i < rec.wires.size(); ++i) {
    if (rec.wires[i].t_s < reset_at_s) continue;
    longest_gap = std::max(longest_gap, rec.wires[i].t_s - rec.wires[i - 1].t_s);
    if (swapped_at_s < 0 && rec.wires[i].sim_time_s < rec.wires[i - 1].sim_time_s) swapped_at_s = rec.wires[i].t_s;
  }
  // the longest run of stale force commands after the reset, in seconds
  int stale = 0, after_reset = 0;
  double stale_since_s = -1, longest_stale_s = 0;
  for (const auto& f : rec.forces) {
    if (f.t_s < reset_at_s) continue;
    ++after_reset;
    if (f.flags & F::FLAG_STALE) {
      ++stale;
      if (stale_since_s < 0) stale_since_s = f.t_s;
      longest_stale_s = std::max(longest_stale_s, f.t_s - stale_since_s + 1e-3);
    } else {
      stale_since_s = -1;
    }
  }
  std::printf(
      "reset at %.2f s, the new world swapped in at %.2f s; the longest gap between wire states %.0f ms; "
      "%d of %d force commands stale after it, the longest run %.0f ms\n",
      reset_at_s, swapped_at_s, 1e3 * longest_gap, stale, after_reset, 1e3 * longest_stale_s);
  EXPECT_GT(swapped_at_s, reset_at_s) << "simulated time starts again: the new world is in";
  EXPECT_LT(longest_gap, 4 * period_s) << "physics kept stepping through the reset";
  ASSERT_GT(after_reset, 500);
  EXPECT_LT(longest_stale_s, 3 * period_s) << "the force model stayed fresh through the reset";
}

// a scene loaded over LCM in a session: its pipeline is built while the running one steps on,
// then takes over (issue #36; before, the session stopped every loop for the whole build, about
// 2 s for the default scene, and the force went stale for as long). The same bounds as the reset's
TEST(SessionCommands, ReloadBuildsTheNextSceneWhileTheRunningOneStepsAndTheForceStaysFresh) {
  DefaultSceneOverMemq rig;
  auto& [lcm, rec, instrument, scene, period_s] = rig;
  SessionLimits limits;
  SessionOptions options;
  options.duration_s = 120.0;  // (the console stops it a second after the handover)
  options.image_url = "memq://";
  std::atomic<bool> stop{false};
  double load_at_s = 0;
  std::thread console([&] {
    // (memq drops what is published before the server subscribes: wait for its wire states)
    auto wait_until = [&](auto&& done) {
      for (int i = 0; i < 1200 && !done(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    };
    wait_until([&] {
      std::lock_guard lock(rec.mutex);
      return rec.wires.size() > 10;
    });
    load_at_s = rec.now_s();
    send(lcm, C::CMD_LOAD_SCENE, PCISIM_SOURCE_DIR "/scenes/default.json");
    wait_until([&] {
      std::lock_guard lock(rec.mutex);
      for (size_t i = 1; i < rec.wires.size(); ++i)
        if (rec.wires[i].t_s > load_at_s && rec.wires[i].sim_time_s < rec.wires[i - 1].sim_time_s) return true;
      return false;
    });
    std::this_thread::sleep_for(std::chrono::seconds(1));
    stop = true;
  });
  StatsReport r;
  ASSERT_NO_THROW(r = run_session(scene, lcm, options, stop, limits));
  console.join();
  std::lock_guard lock(rec.mutex);
  ASSERT_GT(load_at_s, 0.0);
  double longest_gap = 0, swapped_at_s = -1;
  for (size_t i = 1; i < rec.wires.size(); ++i) {
    if (rec.wires[i].t_s < load_at_s) continue;
    longest_gap = std::max(longest_gap, rec.wires[i].t_s - rec.wires[i - 1].t_s);
    if (swapped_at_s < 0 && rec.wires[i].sim_time_s < rec.wires[i - 1].sim_time_s) swapped_at_s = rec.wires[i].t_s;
  }
  // the longest time without a fresh force command after the load: stale, fading or the old
  // pipeline's closing zero (seq -1) are not fresh, nor is a gap while one pipeline hands over to
  // the next. The new pipeline's haptic loop ramps its force in from zero (haptics.ramp_in_ms):
  // fresh, but printed
  double last_fresh_s = load_at_s, longest_stale_s = 0, ramp_s = 0;
  int after_load = 0;
  for (const auto& f : rec.forces) {
    if (f.t_s < load_at_s) continue;
    ++after_load;
    if (f.flags & F::FLAG_RAMPING) ramp_s += 1e-3;
    if ((f.flags & (int{F::FLAG_STALE} | int{F::FLAG_FADED} | int{F::FLAG_FAULT})) || f.seq < 0) continue;
    longest_stale_s = std::max(longest_stale_s, f.t_s - last_fresh_s);
    last_fresh_s = f.t_s;
  }
  std::printf(
      "scene loaded at %.2f s, the new pipeline took over at %.2f s; the longest gap between wire states %.0f ms; "
      "the longest without a fresh force command %.0f ms (%d commands after the load; %.0f ms of them ramping "
      "in)\n",
      load_at_s, swapped_at_s, 1e3 * longest_gap, 1e3 * longest_stale_s, after_load, 1e3 * ramp_s);
  EXPECT_GT(swapped_at_s, load_at_s) << "simulated time starts again: the new pipeline is in";
  EXPECT_LT(longest_gap, 4 * period_s) << "physics kept stepping through the build and the handover";
  ASSERT_GT(after_load, 500);
  EXPECT_LT(longest_stale_s, 3 * period_s) << "the force stayed fresh through the reload";
  EXPECT_EQ(r.scenes_rejected, 0);
}

TEST(SessionCommands, BadSceneIsRefusedGoodSceneEndsTheRunForARestart) {
  lcm::LCM lcm("memq://");
  Instrument instrument(lcm);
  {
    // missing, a name longer than the file system allows, and a FIFO (opening it would block the
    // receive thread): each refused, the session carries on
    const std::string fifo = ::testing::TempDir() + "/pcisim-scene-fifo";
    ::unlink(fifo.c_str());
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    Server server(minimal(), lcm);
    std::thread console([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      send(lcm, C::CMD_LOAD_SCENE, "/nonexistent/scene.json");
      send(lcm, C::CMD_LOAD_SCENE, "/tmp/" + std::string(5000, 'x') + ".json");
      send(lcm, C::CMD_LOAD_SCENE, fifo);
    });
    std::atomic<bool> stop{false};
    const StatsReport r = server.run(1.0, stop);
    console.join();
    ::unlink(fifo.c_str());
    EXPECT_GT(r.elapsed_s, 0.95) << "a refused scene does not interrupt the session";
    EXPECT_LT(r.elapsed_s, 1.5) << "and the server still stops on time";
    EXPECT_FALSE(server.take_requested_scene().has_value());
  }
  {
    Server server(minimal(), lcm);
    std::thread console([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      send(lcm, C::CMD_LOAD_SCENE, PCISIM_SOURCE_DIR "/scenes/default.json");
    });
    std::atomic<bool> stop{false};
    const StatsReport r = server.run(5.0, stop);
    console.join();
    EXPECT_LT(r.elapsed_s, 2.0) << "the run ends so the pipeline restarts with the new scene";
    const auto next = server.take_requested_scene();
    ASSERT_TRUE(next.has_value());
    EXPECT_EQ(next->name, "default");
  }
}

}  // namespace
}  // namespace pcisim::server
