// pcisim-bench debrief: what the session's debrief costs (issue #35: at most 0.1 ms a physics step,
// nothing in the 1 kHz loop). The built-in trainee's session is stepped once through the default
// scene's physics and its wire states kept; then SessionMetrics records them, session after
// session, each call timed (the send thread's cost a physics step); and the end of a session:
// the figures with their lists, debrief.json and debrief.html with a 512 x 512 frame. Writes
// docs/benchmarks/debrief.{md,json}.
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "anatomy/phantom/coronary_phantom.h"
#include "bench/bench_registry.h"
#include "bench/bench_stats.h"
#include "bench/machine_info.h"
#include "bench/trainee_session.h"
#include "physics/world.h"
#include "server/debrief/debrief_page.h"
#include "server/debrief/session_metrics.h"
#include "xray/geometry/c_arm.h"

namespace pcisim::bench {
namespace {

using Clock = std::chrono::steady_clock;
using namespace pcisim::server;
constexpr double kTargetMs = 0.1;  // issue #35: a physics step's share

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

int run(const std::vector<std::string>& args) {
  std::string out_dir = PCISIM_SOURCE_DIR "/docs/benchmarks";
  int sessions = 20;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--out" && i + 1 < args.size()) {
      out_dir = args[++i];
    } else if (args[i] == "--sessions" && i + 1 < args.size()) {
      sessions = std::max(1, std::stoi(args[++i]));
    } else {
      fmt::print(stderr,
                 "usage: pcisim-bench debrief [--out DIR] [--sessions N]\n"
                 "  the debrief's cost: SessionMetrics::record_wire on the built-in trainee's wire states\n"
                 "  (N sessions, default 20), and the end of a session's figures, JSON and page\n");
      return 2;
    }
  }
  // the wire states of the built-in trainee's session in the default (beating) scene
  const physics::WorldSpec spec = default_scene_spec(true);
  physics::World world(spec);
  std::vector<physics::WorldSnapshot> states;
  for (double t = 0.0; t < kSessionS; t += spec.step_s) {
    world.step(session_at(t));
    states.emplace_back();
    world.write_snapshot(states.back());
  }
  fmt::print("debrief: {} wire states of {} nodes\n", states.size(), states.front().wire_nodes_m.size());
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom(anatomy::CoronaryPhantomSpec{spec.anatomy.seed});
  DebriefParams params;
  params.target_branch = "LAD";
  const xray::CArmSpec arm;
  const BeamGeometry beam =
      beam_geometry(arm.source_to_axis_mm, arm.source_to_image_mm, arm.width * arm.pixel_mm, arm.height * arm.pixel_mm);
  std::vector<double> record_ms, end_figures_ms, end_json_ms, end_page_ms;
  std::vector<uint16_t> frame(static_cast<size_t>(arm.width) * arm.height);
  // noise (a linear congruential sequence): the hardest frame for the page's PNG to compress
  uint32_t lcg = 12345;
  for (uint16_t& px : frame) {
    lcg = lcg * 1664525u + 1013904223u;
    px = static_cast<uint16_t>(20000 + (lcg >> 16) % 9000);
  }
  size_t page_bytes = 0;
  for (int session = 0; session < sessions; ++session) {
    SessionMetrics m;
    const int64_t t0 = 1'000'000'000;
    m.begin_pipeline(params, tree, true, beam, t0, arm.width, arm.height);
    m.record_frame(frame.data(), arm.width, arm.height, xray::c_arm_geometry(arm, xray::CArmPose{}), 0.3, 5, t0);
    for (size_t k = 0; k < states.size(); ++k) {
      const auto c0 = Clock::now();
      m.record_wire(states[k], -30, 30, t0 + static_cast<int64_t>(states[k].time_s * 1e9));
      record_ms.push_back(ms_since(c0));
    }
    auto c0 = Clock::now();
    const DebriefFigures f = m.figures(t0 + static_cast<int64_t>(kSessionS * 1e9));
    end_figures_ms.push_back(ms_since(c0));
    c0 = Clock::now();
    const std::string text = to_json(f).dump(2);
    end_json_ms.push_back(ms_since(c0));
    c0 = Clock::now();
    const std::string page = debrief_html(f, nullptr, "bench");
    end_page_ms.push_back(ms_since(c0));
    page_bytes = page.size();
    if (session == 0 && std::getenv("PCISIM_DEBRIEF_BENCH_PAGE"))
      std::ofstream(std::getenv("PCISIM_DEBRIEF_BENCH_PAGE")) << page;
  }
  const double p50 = percentile(record_ms, 0.5), p99 = percentile(record_ms, 0.99);
  const double worst = *std::max_element(record_ms.begin(), record_ms.end());
  const bool met = p99 <= kTargetMs;
  fmt::print(
      "debrief: record_wire p50 {:.4f} / p99 {:.4f} / max {:.4f} ms ({} calls); end: figures {:.2f}, json {:.2f}, "
      "page {:.1f} ms (median)\n",
      p50, p99, worst, record_ms.size(), percentile(end_figures_ms, 0.5), percentile(end_json_ms, 0.5),
      percentile(end_page_ms, 0.5));
  const std::string machine = machine_info();
  nlohmann::json j = {{"machine", machine},
                      {"states_per_session", states.size()},
                      {"nodes", states.front().wire_nodes_m.size()},
                      {"sessions", sessions},
                      {"record_wire_ms", {{"p50", p50}, {"p99", p99}, {"max", worst}}},
                      {"target_ms", kTargetMs},
                      {"met", met},
                      {"end_figures_ms_p50", percentile(end_figures_ms, 0.5)},
                      {"end_json_ms_p50", percentile(end_json_ms, 0.5)},
                      {"end_page_ms_p50", percentile(end_page_ms, 0.5)},
                      {"page_bytes", page_bytes}};
  std::filesystem::create_directories(out_dir);
  std::ofstream(out_dir + "/debrief.json") << j.dump(2) << "\n";
  std::ofstream md(out_dir + "/debrief.md");
  md << "# What the debrief costs\n\n"
     << fmt::format("Generated by `pcisim-bench debrief` (bench/lcm/debrief_bench.cc) on {}.\n\n", machine)
     << fmt::format(
            "The built-in trainee's session ({} wire states of {} nodes, the default beating scene stepped once), "
            "recorded by `SessionMetrics` {} times, each `record_wire` timed: what the LCM send thread spends a "
            "physics step (issue #35's target: {} ms). The 1 kHz loop records nothing. The end of a session (once, "
            "or on `CMD_DEBRIEF`, on the main thread): the figures with their lists, `debrief.json` and "
            "`debrief.html` with a 512 x 512 frame.\n\n",
            states.size(), states.front().wire_nodes_m.size(), sessions, kTargetMs)
     << "| record_wire ms p50 / p99 / max | target | end: figures ms | debrief.json ms | debrief.html ms | page kB |\n"
     << "|---|---|---|---|---|---|\n"
     << fmt::format("| {:.4f} / {:.4f} / {:.4f} | {} | {:.2f} | {:.2f} | {:.1f} | {:.0f} |\n\n", p50, p99, worst,
                    met ? "met" : "missed", percentile(end_figures_ms, 0.5), percentile(end_json_ms, 0.5),
                    percentile(end_page_ms, 0.5), page_bytes / 1024.0)
     << "Medians over the sessions for the end. Not measured here: the haptic loop's figures with the "
        "recording against without it in one run (the loop shares nothing with it; the send thread that "
        "records also carries the force commands, under a priority-inheritance lock).\n";
  fmt::print("debrief: wrote {}/debrief.md and debrief.json\n", out_dir);
  return 0;
}

const bool registered =
    add("debrief", "the session debrief's cost: recording a wire state, the end's JSON and page", run);

}  // namespace
}  // namespace pcisim::bench
