// pcisim-bench stalls: what a trainee would see pause (issue #36), measured in one run on this
// machine and printed as one JSON line (also written to docs/benchmarks/stalls.{md,json}):
//   reset_period_p99_ms      the wire states' period (as a client receives them over memq) from a
//                            CMD_RESET until 1 s after the rebuilt world is in, p99 over the resets
//   reload_period_p99_ms     the same for CMD_LOAD_SCENE of the same scene, through run_session
//   force_stale_max_ms       the longest time without a fresh force command in those windows
//                            (stale-flagged commands, or none at all while pipelines hand over)
//   carm_first_frame_p99_ms  CMD_CARM to the first frame at the new pose arriving (fluoroscopy on:
//                            the wait for the next pulse is part of it)
//   cpu_exact_ms, cpu_trilinear_ms, cpu_planes_ms, plastimatch_exact_ms
//                            512^2 from the thorax phantom (pcisim-bench xray's view), medians;
//                            plastimatch's null where it is not installed (or --plastimatch none)
//   publish_allocations      operator new calls on the publish path once warm: the send thread's
//                            force commands and wire states (LcmIo::publish_forces / publish_wire,
//                            1 010 messages), its status (the scene's server's, 10) and the x-ray
//                            thread's 512^2 frames (XrayLoop, 10)
// The scene is the built-in default with its session's rate limits at 0 (so resets, reloads and
// C-arm moves follow each other at once); a 1 kHz instrument in this process keeps the force live.
//
//   pcisim-bench stalls [--resets N (3)] [--reloads N (2)] [--moves N (20)] [--no-projectors]
//                       [--plastimatch PROGRAM|none] [--out DIR (docs/benchmarks)]
#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "anatomy/phantom/thorax_phantom.h"
#include "bench/bench_registry.h"
#include "bench/bench_stats.h"
#include "bench/machine_info.h"
#include "bench/xray_plastimatch.h"
#include "pcisim_lcm/force_command_t.hpp"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/session_command_t.hpp"
#include "pcisim_lcm/wire_state_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"
#include "protocol/channels.h"
#include "protocol/message_checks.h"
#include "realtime/allocation_count.h"
#include "realtime/clock.h"
#include "server/case_builder.h"
#include "server/lcm_io.h"
#include "server/server.h"
#include "server/session_runner.h"
#include "server/xray_loop.h"
#include "xray/projectors/siddon_projector.h"
#include "xray/projectors/trilinear_projector.h"

namespace pcisim::bench {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using C = pcisim_lcm::session_command_t;
using namespace std::chrono_literals;

struct Options {
  int resets = 3, reloads = 2, moves = 20;
  bool projectors = true;
  std::string plastimatch = "auto";
  std::string out_dir = PCISIM_SOURCE_DIR "/docs/benchmarks";
};

double now_s() {
  return realtime::monotonic_ns() * 1e-9;
}

// what the server sends, stamped on arrival
struct Listener {
  struct Wire {
    double t_s, sim_time_s;
  };
  struct Force {
    double t_s;
    bool fresh, ramping;
  };
  struct Frame {
    double t_s, primary_deg, secondary_deg, sent_s;
  };
  std::mutex mutex;
  std::vector<Wire> wires;
  std::vector<Force> forces;
  std::vector<Frame> frames;

  void on_wire(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::wire_state_t m;
    if (!protocol::decode_checked(*r, m)) return;
    std::lock_guard lock(mutex);
    wires.push_back({now_s(), m.sim_time_s});
  }
  void on_force(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::force_command_t m;
    if (!protocol::decode_checked(*r, m)) return;
    std::lock_guard lock(mutex);
    // fresh: the loop's own force from a model in date (not stale, fading or faulted, not the
    // closing zero a stopping pipeline sends with seq -1); ramping in is fresh, counted apart
    using F = pcisim_lcm::force_command_t;
    const bool fresh = (m.flags & (int{F::FLAG_STALE} | int{F::FLAG_FADED} | int{F::FLAG_FAULT})) == 0 && m.seq >= 0;
    forces.push_back({now_s(), fresh, (m.flags & F::FLAG_RAMPING) != 0});
  }
  void on_frame(const lcm::ReceiveBuffer* r, const std::string&) {
    pcisim_lcm::xray_frame_t m;
    if (!protocol::decode_checked(*r, m)) return;
    std::lock_guard lock(mutex);
    frames.push_back({now_s(), m.primary_angle_deg, m.secondary_angle_deg, m.utime * 1e-6});
  }
  size_t wire_count() {
    std::lock_guard lock(mutex);
    return wires.size();
  }
  // the arrival of the first wire state after `since_s` whose simulated time went back (a new
  // world), or nullopt
  std::optional<double> new_world_after(double since_s) {
    std::lock_guard lock(mutex);
    for (size_t i = 1; i < wires.size(); ++i)
      if (wires[i].t_s > since_s && wires[i].sim_time_s < wires[i - 1].sim_time_s) return wires[i].t_s;
    return std::nullopt;
  }
  // within [from_s, to_s]: the periods between wire states (appended), the longest time without
  // a fresh force command (returned) and the time the force ramped in (*ramp_ms, 1 ms a command)
  double window(double from_s, double to_s, std::vector<double>* periods_ms, double* ramp_ms) {
    std::lock_guard lock(mutex);
    for (size_t i = 1; i < wires.size(); ++i)
      if (wires[i].t_s > from_s && wires[i].t_s <= to_s) periods_ms->push_back(1e3 * (wires[i].t_s - wires[i - 1].t_s));
    double last_fresh_s = from_s, stale_ms = 0;
    *ramp_ms = 0;
    for (const auto& f : forces) {
      if (f.t_s < from_s || f.t_s > to_s) continue;
      if (f.ramping) *ramp_ms += 1.0;
      if (!f.fresh) continue;
      stale_ms = std::max(stale_ms, 1e3 * (f.t_s - last_fresh_s));
      last_fresh_s = f.t_s;
    }
    return std::max(stale_ms, 1e3 * (to_s - last_fresh_s));
  }
};

void send(lcm::LCM& lcm, int8_t command, const std::string& path = "", double primary = 0, double secondary = 0,
          bool pedal = false) {
  C m{};
  m.command = command;
  m.scene_path = path;
  m.primary_angle_deg = primary;
  m.secondary_angle_deg = secondary;
  m.pedal_down = pedal ? 1 : 0;
  lcm.publish(protocol::kSessionChannel, &m);
}

// a steady instrument at 1 kHz while it lives (without one the haptic loop fades the force)
class Instrument {
 public:
  explicit Instrument(lcm::LCM& lcm)
      : thread_([this, &lcm] {
          pcisim_lcm::instrument_state_t m{};
          for (int64_t seq = 0; !done_; ++seq) {
            m.seq = seq;
            m.utime = realtime::monotonic_us();
            lcm.publish(protocol::kInstrumentChannel, &m);
            std::this_thread::sleep_for(1ms);
          }
        }) {}
  ~Instrument() {
    done_ = true;
    thread_.join();
  }

 private:
  std::atomic<bool> done_{false};
  std::thread thread_;
};

// waits until `ready` or `timeout_s`; false on the timeout
template <class Fn>
bool wait_for(Fn&& ready, double timeout_s) {
  const double end_s = now_s() + timeout_s;
  while (!ready()) {
    if (now_s() > end_s) return false;
    std::this_thread::sleep_for(5ms);
  }
  return true;
}

// the default scene with the session's rate limits at 0, written where run_session can reload it
std::string write_scene(const std::string& dir) {
  std::ifstream in(PCISIM_SOURCE_DIR "/scenes/default.json");
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const std::string anchor = "\"name\": \"default\",";
  const size_t at = s.find(anchor);
  if (at == std::string::npos)
    throw std::runtime_error("scenes/default.json: no '" + anchor + "' to add the limits to");
  s.insert(at + anchor.size(),
           " \"session\": {\"min_reset_interval_s\": 0, \"min_scene_load_interval_s\": 0, "
           "\"min_carm_move_interval_s\": 0},");
  const std::string path = dir + "/stalls-default.json";
  std::ofstream(path) << s;
  return path;
}

struct Figures {
  std::vector<double> reset_periods_ms, reload_periods_ms, carm_ms, reset_swap_ms, reload_swap_ms;
  double force_stale_max_ms = 0, reset_stale_ms = 0, reload_stale_ms = 0, reload_ramp_ms = 0;
  int resets_done = 0, reloads_done = 0, moves_done = 0;
  std::optional<double> cpu_exact_ms, cpu_trilinear_ms, cpu_planes_ms, plastimatch_exact_ms;
  std::string plastimatch_why;
  long publish_allocations = -1;
  int publish_messages = 0;
};

// resets and C-arm moves on one server
void measure_resets_and_moves(const server::Scene& scene, const Options& o, Figures* f) {
  lcm::LCM lcm("memq://");
  Listener rx;
  lcm.subscribe(protocol::kWireChannel, &Listener::on_wire, &rx);
  lcm.subscribe(protocol::kForceChannel, &Listener::on_force, &rx);
  lcm.subscribe(protocol::kXrayChannel, &Listener::on_frame, &rx);
  Instrument instrument(lcm);
  server::Server server(scene, lcm, &lcm);
  std::atomic<bool> stop{false};
  std::thread run([&] { server.run(0, stop); });
  wait_for([&] { return rx.wire_count() > 30; }, 60);
  for (int k = 0; k < o.resets; ++k) {
    const double t0 = now_s();
    send(lcm, C::CMD_RESET);
    if (!wait_for([&] { return rx.new_world_after(t0).has_value(); }, 60)) break;
    const double swapped = *rx.new_world_after(t0);
    std::this_thread::sleep_for(1s);
    double ramp_ms = 0;
    f->reset_stale_ms = std::max(f->reset_stale_ms, rx.window(t0, now_s(), &f->reset_periods_ms, &ramp_ms));
    f->force_stale_max_ms = std::max(f->force_stale_max_ms, f->reset_stale_ms);
    f->reset_swap_ms.push_back(1e3 * (swapped - t0));
    ++f->resets_done;
    std::fprintf(stderr, "stalls: reset %d: the new world in after %.0f ms\n", k + 1, 1e3 * (swapped - t0));
  }
  send(lcm, C::CMD_FLUORO_PEDAL, "", 0, 0, true);
  std::this_thread::sleep_for(1s);
  for (int k = 0; k < o.moves; ++k) {
    // a pose not shown before in the run (the background of each is projected anew), within the
    // C-arm's range for any number of moves
    const double primary = -170.0 + std::fmod(130.0 + 9.0 * k, 340.0), secondary = 30.0 - std::fmod(5.0 * k, 120.0);
    const double t0 = now_s();
    send(lcm, C::CMD_CARM, "", primary, secondary);
    std::optional<double> first;
    double sent = 0;
    wait_for(
        [&] {
          std::lock_guard lock(rx.mutex);
          for (const auto& fr : rx.frames)
            if (fr.t_s > t0 && std::abs(fr.primary_deg - primary) < 1e-9 &&
                std::abs(fr.secondary_deg - secondary) < 1e-9)
              if (!first) {
                first = fr.t_s;
                sent = fr.sent_s;
              }
          return first.has_value();
        },
        10);
    if (!first) break;
    f->carm_ms.push_back(1e3 * (*first - t0));
    ++f->moves_done;
    std::fprintf(stderr, "stalls: C-arm move %d to (%.0f, %.0f): first frame after %.0f ms (sent after %.0f)\n", k + 1,
                 primary, secondary, 1e3 * (*first - t0), 1e3 * (sent - t0));
    std::this_thread::sleep_for(1200ms);  // the projection made whole and the bins filled
  }
  stop = true;
  run.join();
}

// scene reloads through the session runner (its successor built while it runs)
void measure_reloads(const server::Scene& scene, const std::string& scene_path, const Options& o, Figures* f) {
  lcm::LCM lcm("memq://");
  Listener rx;
  lcm.subscribe(protocol::kWireChannel, &Listener::on_wire, &rx);
  lcm.subscribe(protocol::kForceChannel, &Listener::on_force, &rx);
  Instrument instrument(lcm);
  std::atomic<bool> stop{false};
  std::thread console([&] {
    if (wait_for([&] { return rx.wire_count() > 30; }, 60)) {
      for (int k = 0; k < o.reloads; ++k) {
        const double t0 = now_s();
        send(lcm, C::CMD_LOAD_SCENE, scene_path);
        if (!wait_for([&] { return rx.new_world_after(t0).has_value(); }, 120)) break;
        const double swapped = *rx.new_world_after(t0);
        std::this_thread::sleep_for(1s);
        double ramp_ms = 0;
        f->reload_stale_ms = std::max(f->reload_stale_ms, rx.window(t0, now_s(), &f->reload_periods_ms, &ramp_ms));
        f->reload_ramp_ms = std::max(f->reload_ramp_ms, ramp_ms);
        f->force_stale_max_ms = std::max(f->force_stale_max_ms, f->reload_stale_ms);
        f->reload_swap_ms.push_back(1e3 * (swapped - t0));
        ++f->reloads_done;
        std::fprintf(stderr, "stalls: reload %d: the new pipeline in after %.0f ms\n", k + 1, 1e3 * (swapped - t0));
      }
    }
    stop = true;
  });
  server::SessionLimits limits;
  server::SessionOptions options;
  options.image_url = "memq://";
  try {
    server::run_session(scene, lcm, options, stop, limits);
  } catch (...) {
    stop = true;
    console.join();
    throw;
  }
  console.join();
}

// the send thread's streams, counted as LcmIoPublish's test counts them
void measure_publish(const server::Scene& scene, Figures* f) {
  lcm::LCM lcm("memq://");
  server::SharedState state;
  server::SessionLimits limits;
  static const std::string branch = "a branch name longer than fifteen characters";
  // the status as the scene's server gathers it (its world and fluoroscopy built: seconds)
  server::Server status_server(scene, lcm);
  server::LcmIo io(
      lcm, state, limits, 8.0, [&](pcisim_lcm::sim_status_t& m) { status_server.fill_status(&m); },
      [](int) -> const std::string& { return branch; });
  physics::WorldSnapshot snap;
  snap.wire_nodes_m.assign(201, Eigen::Vector3d(0.001, 0.002, 0.003));
  snap.wire_contact.assign(201, 1);
  snap.wire_contact_force_n.assign(201, Eigen::Vector3d(0.0, 0.01, 0.0));
  auto push = [&](int n) {
    for (int k = 0; k < n; ++k) {
      server::ForceSlot slot;
      slot.tick = k;
      slot.force.axial_force_n = 0.01 * k;
      state.forces.push(slot);
    }
  };
  push(10);  // warm: the messages and their buffers take their sizes
  io.publish_forces();
  io.publish_wire(snap);
  io.publish_status();
  realtime::AllocationCount count;
  for (int round = 0; round < 10; ++round) {
    push(100);
    io.publish_forces();
    io.publish_wire(snap);
    io.publish_status();
  }
  long allocations = count.allocations();
  // the scene's x-ray frames (512^2, still background), rendered and published on the image
  // instance by the x-ray thread's own path, once warm
  const auto anatomy = server::build_case(scene);
  lcm::LCM images("memq://");
  server::XrayLoop xray(scene, *anatomy, state, &images);
  physics::WorldSnapshot& frame_snap = state.snapshot_for_xray.write_slot();
  frame_snap = snap;
  state.snapshot_for_xray.publish();
  for (int k = 0; k < 3; ++k) xray.render_and_publish(false);
  {
    realtime::AllocationCount frames;
    for (int k = 0; k < 10; ++k) xray.render_and_publish(false);
    allocations += frames.allocations();
  }
  f->publish_allocations = allocations;
  f->publish_messages = 10 * 102 + 10;
}

// the CPU projectors and plastimatch on pcisim-bench xray's view
void measure_projectors(const Options& o, Figures* f) {
  using namespace pcisim::xray;
  anatomy::ThoraxPhantomSpec spec;  // 512 x 512 x 256 at 0.7 mm
  const anatomy::Volume volume = anatomy::make_thorax_phantom(spec);
  const AttenuationVolume att(volume);
  CArmSpec c;
  c.width = c.height = 512;
  c.pixel_mm = 0.4;
  const CArmPose pose{30, 20, Eigen::Vector3d::Zero()};
  const DetectorGeometry g = c_arm_geometry(c, pose);
  Image exact_image, img;
  exact_image.resize(512, 512);
  img.resize(512, 512);
  auto median_ms = [](int frames, auto&& fn) {
    fn();  // warm-up
    std::vector<double> ms;
    for (int i = 0; i < frames; ++i) {
      const int64_t t0 = realtime::monotonic_ns();
      fn();
      ms.push_back((realtime::monotonic_ns() - t0) * 1e-6);
    }
    return percentile(ms, 0.5);
  };
  SiddonProjector exact(att);
  f->cpu_exact_ms = median_ms(5, [&] { exact.project(g, &exact_image); });
  TrilinearProjector trilinear(att, {.step_voxels = 1.0, .skip_empty = true});
  f->cpu_trilinear_ms = median_ms(5, [&] { trilinear.project(g, &img); });
  // the scenes' CPU projector: one sample per voxel plane (Joseph's method; its error against
  // exact: docs/benchmarks/xray.md)
  TrilinearProjector planes(att, {.skip_empty = true, .slices = true});
  f->cpu_planes_ms = median_ms(5, [&] { planes.project(g, &img); });
  std::fprintf(stderr, "stalls: 512^2 exact %.0f ms, trilinear (1 voxel) %.0f ms, voxel planes %.0f ms\n",
               *f->cpu_exact_ms, *f->cpu_trilinear_ms, *f->cpu_planes_ms);
  const std::string program = o.plastimatch == "auto" ? find_plastimatch() : o.plastimatch;
  if (o.plastimatch == "none" || program.empty()) {
    f->plastimatch_why = o.plastimatch == "none" ? "--plastimatch none" : "plastimatch is not installed";
    return;
  }
  const std::string work = o.out_dir + "/.stalls-plastimatch";
  const PlastimatchRun pm = run_plastimatch_drr(program, att, volume, c, pose, exact_image, work, 3);
  fs::remove_all(work);
  if (pm.ran) {
    f->plastimatch_exact_ms = pm.per_image_ms;
    std::fprintf(stderr, "stalls: plastimatch exact %.0f ms (correlation %.6f)\n", pm.per_image_ms, pm.correlation);
  } else {
    f->plastimatch_why = pm.why;
  }
}

json or_null(const std::optional<double>& v) {
  return v ? json(std::round(*v * 10) / 10) : json(nullptr);
}

double p99_or_nan(const std::vector<double>& v) {
  return v.empty() ? NAN : percentile(v, 0.99);
}

void write_report(const Options& o, const Figures& f, const json& line, const std::string& machine) {
  fs::create_directories(o.out_dir);
  std::ofstream(o.out_dir + "/stalls.json") << line.dump(2) << "\n";
  std::ofstream md(o.out_dir + "/stalls.md");
  const auto p50 = [](const std::vector<double>& v) { return v.empty() ? NAN : percentile(v, 0.5); };
  const auto met = [](bool ok) { return ok ? "met" : "missed"; };
  const double reset_p99 = p99_or_nan(f.reset_periods_ms), reload_p99 = p99_or_nan(f.reload_periods_ms);
  const double carm_p99 = p99_or_nan(f.carm_ms);
  md << "# What a trainee sees pause: resets, reloads, C-arm moves, projectors, allocation\n\n";
  md << fmt::format("Generated by `pcisim-bench stalls` (bench/lcm/stalls_bench.cc) on {}.\n\n", machine);
  md << "The built-in default scene (beating heart, moving tree, contact field at 0.2 mm, fluoroscopy at 512^2, "
        "15 pulses/s) with its session's rate limits at 0, run in this process over memq with a 1 kHz instrument; "
        "times are arrivals at a subscriber. Issue #36's targets, on the machine above. One run: this shared 2-core "
        "machine's own jitter moves the tails from run to run (an 11 ms loop alone has measured up to 72 ms "
        "here), so a tail near its bound may read met in one run and missed in the next.\n\n";
  md << "| what | measured | target | |\n|---|---|---|---|\n";
  md << fmt::format(
      "| physics period during a reset (wire states' period from CMD_RESET to 1 s after the swap, p99 over {} "
      "resets) | {:.1f} ms (new world in after {:.0f} ms median) | <= 40 ms | {} |\n",
      f.resets_done, reset_p99, p50(f.reset_swap_ms), met(reset_p99 <= 40));
  md << fmt::format(
      "| physics period during a scene reload (CMD_LOAD_SCENE of the same scene, through run_session, p99 over {} "
      "reloads) | {:.1f} ms (the new pipeline, built while the old one ran, in after {:.0f} ms median) | <= 40 ms | "
      "{} |\n",
      f.reloads_done, reload_p99, p50(f.reload_swap_ms), met(reload_p99 <= 40));
  md << fmt::format(
      "| longest without a fresh force command in those windows (resets {:.1f} ms, reloads {:.1f} ms) | {:.1f} ms | "
      "<= 50 ms | {} |\n",
      f.reset_stale_ms, f.reload_stale_ms, f.force_stale_max_ms, met(f.force_stale_max_ms <= 50));
  md << fmt::format(
      "| after a reload the new pipeline's haptic loop ramps its force in from zero (haptics.ramp_in_ms, fresh "
      "but weaker: what the hand feels) | {:.0f} ms | - | |\n",
      f.reload_ramp_ms);
  md << fmt::format(
      "| CMD_CARM to the first frame at the new pose arriving ({} moves to poses not shown before; median {:.0f} "
      "ms; the x-ray loop renders a due move at once, its quick projection first) | {:.0f} ms p99 | <= 100 ms | {} "
      "|\n",
      f.moves_done, p50(f.carm_ms), carm_p99, met(carm_p99 <= 100));
  if (f.cpu_exact_ms) {
    md << fmt::format(
        "| CPU exact DRR, 512^2 from the thorax phantom (512 x 512 x 256), median of 5 | {:.0f} ms | "
        "<= 0.5 x plastimatch's | {} |\n",
        *f.cpu_exact_ms,
        f.plastimatch_exact_ms ? met(*f.cpu_exact_ms <= 0.5 * *f.plastimatch_exact_ms) : "not compared");
    md << fmt::format(
        "| plastimatch drr -i exact, same volume and view, median of 3 | {} | - | |\n",
        f.plastimatch_exact_ms ? fmt::format("{:.0f} ms", *f.plastimatch_exact_ms) : "not run: " + f.plastimatch_why);
    md << fmt::format("| CPU trilinear DRR at a 1-voxel step, median of 5 | {:.0f} ms | <= 100 ms | {} |\n",
                      *f.cpu_trilinear_ms, met(*f.cpu_trilinear_ms <= 100));
    md << fmt::format(
        "| the same DRR one sample per voxel plane (Joseph's method, the scenes' CPU projector; its error against "
        "exact beside trilinear's: docs/benchmarks/xray.md), median of 5 | {:.0f} ms | <= 100 ms | {} |\n",
        *f.cpu_planes_ms, met(*f.cpu_planes_ms <= 100));
  }
  md << fmt::format(
      "| operator new on the publish path (force commands, wire states and the status of the send thread, and the "
      "x-ray thread's 512^2 frames: {} messages) | {} | 0 | {} |\n\n",
      f.publish_messages, f.publish_allocations, met(f.publish_allocations == 0));
  md << "Not measured here: the GPU projector (docs/benchmarks/xray.md, xray.earlier.md).\n\n";
  md << "The JSON line:\n\n```\n" << line.dump() << "\n```\n";
}

int run(const std::vector<std::string>& args) {
  Options o;
  for (size_t i = 0; i < args.size(); ++i) {
    const bool more = i + 1 < args.size();
    if (args[i] == "--resets" && more) {
      o.resets = std::max(0, std::atoi(args[++i].c_str()));
    } else if (args[i] == "--reloads" && more) {
      o.reloads = std::max(0, std::atoi(args[++i].c_str()));
    } else if (args[i] == "--moves" && more) {
      o.moves = std::max(0, std::atoi(args[++i].c_str()));
    } else if (args[i] == "--no-projectors") {
      o.projectors = false;
    } else if (args[i] == "--plastimatch" && more) {
      o.plastimatch = args[++i];
    } else if (args[i] == "--out" && more) {
      o.out_dir = args[++i];
    } else {
      std::printf(
          "pcisim-bench stalls [--resets N (3)] [--reloads N (2)] [--moves N (20)] [--no-projectors]\n"
          "                    [--plastimatch PROGRAM|none (the first on PATH)] [--out DIR (docs/benchmarks)]\n"
          "  issue #36's pauses in one run on this machine, one JSON line: reset_period_p99_ms,\n"
          "  reload_period_p99_ms, force_stale_max_ms, carm_first_frame_p99_ms, cpu_exact_ms,\n"
          "  cpu_trilinear_ms, cpu_planes_ms, plastimatch_exact_ms (null without plastimatch),\n"
          "  publish_allocations;\n"
          "  writes DIR/stalls.{md,json}. The default scene runs in this process over memq (~1 min),\n"
          "  the projectors on the thorax phantom (~1 min more; --no-projectors skips them)\n");
      return args[i] == "--help" ? 0 : 2;
    }
  }
  const std::string machine = machine_info();
  std::fprintf(stderr, "stalls: %s\n", machine.c_str());
  const std::string dir = fs::temp_directory_path() / ("pcisim-stalls-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  Figures f;
  try {
    const std::string scene_path = write_scene(dir);
    const server::Scene scene = server::load_scene_file(scene_path);
    measure_resets_and_moves(scene, o, &f);
    measure_reloads(scene, scene_path, o, &f);
    measure_publish(scene, &f);
    if (o.projectors) measure_projectors(o, &f);
  } catch (const std::exception& e) {
    fs::remove_all(dir);
    std::fprintf(stderr, "stalls: %s\n", e.what());
    return 1;
  }
  fs::remove_all(dir);
  auto rounded = [](double v) { return std::isfinite(v) ? json(std::round(v * 10) / 10) : json(nullptr); };
  const json line = {{"reset_period_p99_ms", rounded(p99_or_nan(f.reset_periods_ms))},
                     {"reload_period_p99_ms", rounded(p99_or_nan(f.reload_periods_ms))},
                     {"force_stale_max_ms", rounded(f.force_stale_max_ms)},
                     {"reload_ramp_in_ms", rounded(f.reload_ramp_ms)},
                     {"carm_first_frame_p99_ms", rounded(p99_or_nan(f.carm_ms))},
                     {"cpu_exact_ms", or_null(f.cpu_exact_ms)},
                     {"cpu_trilinear_ms", or_null(f.cpu_trilinear_ms)},
                     {"cpu_planes_ms", or_null(f.cpu_planes_ms)},
                     {"plastimatch_exact_ms", or_null(f.plastimatch_exact_ms)},
                     {"publish_allocations", f.publish_allocations},
                     {"resets", f.resets_done},
                     {"reloads", f.reloads_done},
                     {"carm_moves", f.moves_done}};
  std::printf("%s\n", line.dump().c_str());
  write_report(o, f, line, machine);
  const bool complete = f.resets_done == o.resets && f.reloads_done == o.reloads && f.moves_done == o.moves;
  if (!complete) std::fprintf(stderr, "stalls: not every reset, reload or move completed\n");
  return complete ? 0 : 1;
}

const bool registered = add("stalls", "issue #36's pauses: reset, reload, C-arm move, projectors, allocation", run);

}  // namespace
}  // namespace pcisim::bench
