// pcisim-bench guidewire: what chain-mail accuracy costs. The default scene's wire (300 mm,
// 12 mm tip at 45 deg, contact + friction + blood flow, phantom seed 1, 30 Hz) runs the built-in
// trainee's session into the LAD (insert 8 mm, turn 90 deg, advance 50 mm, pull 5 mm) for every
// setting of segments x optimisation passes x SDF spacing. Per setting: median and p99 of the
// wall time of World::step (and of the thread's CPU time, which other processes cannot inflate),
// the tip's RMS distance over the session from the finest setting's tip, and the deepest any
// free node ended a step outside the lumen, measured on the finest SDF. Writes guidewire.md,
// guidewire.json and (with python3-matplotlib) guidewire.png into docs/benchmarks/ or --out DIR.
#include <fmt/format.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "bench/bench_options.h"
#include "bench/bench_registry.h"
#include "bench/bench_stats.h"
#include "bench/machine_info.h"
#include "bench/trainee_session.h"
#include "physics/guidewire/chain_mail_wire.h"
#include "physics/guidewire/sdf_lumen.h"
#include "anatomy/phantom/coronary_phantom.h"
#include "physics/world.h"

namespace pcisim::bench {
namespace {

using namespace pcisim::physics;

struct Setting {
  int segments = 200;
  int passes = 2;
  double spacing_mm = 0.2;
};

struct Row {
  Setting s;
  double median_ms = 0, p99_ms = 0, max_ms = 0;
  double cpu_median_ms = 0, cpu_p99_ms = 0;
  double tip_rms_mm = 0, tip_final_mm = 0, max_penetration_mm = 0;
  std::string final_branch;
  int steps = 0;
};

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

WorldSpec scene(const Setting& s) {
  WorldSpec spec;
  spec.step_s = 1.0 / 30.0;
  spec.guidewire = GuidewireParams{};
  spec.guidewire->segment_count = s.segments;
  spec.guidewire->optimisation_passes = s.passes;
  spec.vessel_contact = VesselContactParams{};
  spec.vessel_contact->sdf_spacing_m = s.spacing_mm * 1e-3;
  spec.friction = FrictionParams{};
  spec.blood_flow = BloodFlowParams{};
  return spec;
}

// runs the session; fills timing, penetration and the tip trajectory
Row run(const Setting& s, std::shared_ptr<const LumenQuery> lumen, const LumenQuery& reference,
        std::vector<Eigen::Vector3d>& tips) {
  Row r;
  r.s = s;
  World world(scene(s), std::move(lumen));
  const double dt = 1.0 / 30.0;
  std::vector<double> wall, cpu;
  tips.clear();
  double worst = -1.0;
  for (int k = 0; k * dt <= kSessionS; ++k) {
    const InstrumentInput in = session_at(k * dt);
    const double c0 = thread_cpu_ms();
    const auto t0 = std::chrono::steady_clock::now();
    world.step(in);
    const auto t1 = std::chrono::steady_clock::now();
    const double c1 = thread_cpu_ms();
    wall.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    cpu.push_back(c1 - c0);
    const ChainMailWire& w = *world.guidewire_state();
    const auto x = w.nodes_m();
    for (int i = w.first_free_node(); i < w.node_count(); ++i)
      worst = std::max(worst, reference.sample(x[i]).distance_m);
    tips.push_back(x.back());
  }
  WorldSnapshot snap;
  world.write_snapshot(snap);
  r.final_branch = snap.tip_branch >= 0 ? world.vessel_tree().branches[snap.tip_branch].name : "-";
  r.steps = static_cast<int>(wall.size());
  r.median_ms = percentile(wall, 0.5);
  r.p99_ms = percentile(wall, 0.99);
  r.max_ms = percentile(wall, 1.0);
  r.cpu_median_ms = percentile(cpu, 0.5);
  r.cpu_p99_ms = percentile(cpu, 0.99);
  r.max_penetration_mm = std::max(worst, 0.0) * 1e3;
  return r;
}

constexpr const char* kUsage =
    "usage: pcisim-bench guidewire [--quick] [--out DIR] [--no-plot]\n"
    "  sweeps segments {50,100,200,400,800} x passes {1,2,4,8} x SDF spacing {0.1,0.2,0.4} mm\n"
    "  (--quick: segments {50,200,800} x passes {1,2,8} x spacing {0.2,0.4}) over the built-in\n"
    "  trainee's LAD session; writes guidewire.md/.json/.png into DIR (docs/benchmarks)\n";

int run_bench(const std::vector<std::string>& args) {
  BenchOptions o;
  if (const int rc = parse_bench_options(args, "guidewire", kUsage, &o); rc >= 0) return rc;
  std::filesystem::create_directories(o.out_dir);
  const std::string machine = machine_info();
  std::printf("guidewire: %s\n", machine.c_str());

  const std::vector<int> segments = o.quick ? std::vector<int>{50, 200, 800} : std::vector<int>{50, 100, 200, 400, 800};
  const std::vector<int> passes = o.quick ? std::vector<int>{1, 2, 8} : std::vector<int>{1, 2, 4, 8};
  const std::vector<double> spacings = o.quick ? std::vector<double>{0.2, 0.4} : std::vector<double>{0.1, 0.2, 0.4};
  const Setting finest{800, 8, 0.1};

  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({1});
  std::map<double, std::shared_ptr<const SdfLumen>> fields;
  std::map<double, double> build_ms;
  auto field = [&](double spacing_mm) {
    auto it = fields.find(spacing_mm);
    if (it != fields.end()) return it->second;
    const auto t0 = std::chrono::steady_clock::now();
    auto f = std::make_shared<const SdfLumen>(tree, spacing_mm * 1e-3);
    build_ms[spacing_mm] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("guidewire: SDF at %.1f mm built in %.0f ms (%.1f MB)\n", spacing_mm, build_ms[spacing_mm],
                f->field().memory_bytes() / 1e6);
    return fields[spacing_mm] = f;
  };
  const auto reference = field(finest.spacing_mm);

  // the reference run first: every other tip is compared with its trajectory
  std::vector<Eigen::Vector3d> ref_tips, tips;
  Row ref_row = run(finest, reference, *reference, ref_tips);
  std::printf("guidewire: reference %d segments, %d passes, %.1f mm: tip ends in %s\n", finest.segments, finest.passes,
              finest.spacing_mm, ref_row.final_branch.c_str());

  std::vector<Row> rows;
  for (double sp : spacings) {
    const auto lumen = field(sp);
    for (int n : segments) {
      for (int p : passes) {
        const Setting s{n, p, sp};
        const bool is_ref = n == finest.segments && p == finest.passes && sp == finest.spacing_mm;
        Row r = is_ref ? ref_row : run(s, lumen, *reference, tips);
        const std::vector<Eigen::Vector3d>& tt = is_ref ? ref_tips : tips;
        const size_t m = std::min(tt.size(), ref_tips.size());
        double sum = 0.0;
        for (size_t k = 0; k < m; ++k) sum += (tt[k] - ref_tips[k]).squaredNorm();
        r.tip_rms_mm = m ? std::sqrt(sum / m) * 1e3 : 0.0;
        r.tip_final_mm = m ? (tt[m - 1] - ref_tips[m - 1]).norm() * 1e3 : 0.0;
        rows.push_back(r);
        std::printf(
            "guidewire: %4d seg %d pass %.1f mm: median %.3f ms p99 %.3f ms (cpu p99 %.3f)  tip rms %.2f mm  "
            "pen %.3f mm  -> %s\n",
            n, p, sp, r.median_ms, r.p99_ms, r.cpu_p99_ms, r.tip_rms_mm, r.max_penetration_mm, r.final_branch.c_str());
      }
    }
  }

  // json
  {
    std::ofstream f(o.out_dir + "/guidewire.json");
    f << "{\n" << fmt::format("  \"machine\": \"{}\",\n  \"quick\": {},\n", machine, o.quick);
    f << "  \"session\": \"built-in trainee, turn 90 deg toward the LAD, 19.5 s at 30 Hz\",\n";
    f << fmt::format("  \"reference\": {{\"segments\": {}, \"passes\": {}, \"sdf_spacing_mm\": {}}},\n",
                     finest.segments, finest.passes, finest.spacing_mm);
    f << "  \"sdf_build_ms\": {";
    bool first = true;
    for (const auto& [sp, ms] : build_ms) {
      f << fmt::format("{}\"{}\": {:.1f}", first ? "" : ", ", sp, ms);
      first = false;
    }
    f << "},\n  \"rows\": [\n";
    for (size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      f << fmt::format(
          "    {{\"segments\": {}, \"passes\": {}, \"sdf_spacing_mm\": {}, \"steps\": {}, \"median_ms\": {:.4f}, "
          "\"p99_ms\": {:.4f}, \"max_ms\": {:.4f}, \"cpu_median_ms\": {:.4f}, \"cpu_p99_ms\": {:.4f}, "
          "\"tip_rms_mm\": {:.4f}, \"tip_final_mm\": {:.4f}, \"max_penetration_mm\": {:.4f}, \"final_branch\": "
          "\"{}\"}}{}\n",
          r.s.segments, r.s.passes, r.s.spacing_mm, r.steps, r.median_ms, r.p99_ms, r.max_ms, r.cpu_median_ms,
          r.cpu_p99_ms, r.tip_rms_mm, r.tip_final_mm, r.max_penetration_mm, r.final_branch,
          i + 1 < rows.size() ? "," : "");
    }
    f << "  ]\n}\n";
  }
  // markdown
  {
    std::ofstream f(o.out_dir + "/guidewire.md");
    f << "# Guidewire (chain-mail) benchmark\n\n";
    f << fmt::format("Generated by `pcisim-bench guidewire{}` on {}; single-threaded.\n\n", o.quick ? " --quick" : "",
                     machine);
    f << "Scene: the default (phantom seed 1, 300 mm wire, 12 mm tip at 45 deg, contact + friction + blood flow, "
         "30 Hz). Session: the built-in trainee toward the LAD (insert 8 mm over 3 s, turn 90 deg over 2 s, advance "
         "50 mm over 10 s, pull 5 mm), "
      << rows.front().steps << " steps.\n\n";
    f << fmt::format(
        "Reference: {} segments, {} passes, SDF {} mm. Tip error: RMS over the session of the distance "
        "between the tip and the reference's tip at the same step. Penetration: the deepest any free node "
        "ended a step outside the lumen, measured on the {} mm SDF (the wall margin is 0.05 mm inside). "
        "Times: wall clock of `World::step` (median, p99), and the calling thread's CPU time (p99), which "
        "other processes on the machine cannot inflate.\n\n",
        finest.segments, finest.passes, finest.spacing_mm, finest.spacing_mm);
    f << "SDF builds (once per spacing, not in the step):";
    for (const auto& [sp, ms] : build_ms) f << fmt::format(" {} mm {:.0f} ms;", sp, ms);
    f << "\n\n";
    f << "| segments | passes | SDF mm | median ms | p99 ms | CPU p99 ms | tip RMS mm | tip final mm | penetration mm "
         "| tip ends in |\n";
    f << "|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows) {
      f << fmt::format("| {} | {} | {} | {:.3f} | {:.3f} | {:.3f} | {:.2f} | {:.2f} | {:.3f} | {} |\n", r.s.segments,
                       r.s.passes, r.s.spacing_mm, r.median_ms, r.p99_ms, r.cpu_p99_ms, r.tip_rms_mm, r.tip_final_mm,
                       r.max_penetration_mm, r.final_branch);
    }
    auto find = [&](int n, int p, double sp) -> const Row* {
      for (const Row& r : rows)
        if (r.s.segments == n && r.s.passes == p && r.s.spacing_mm == sp) return &r;
      return nullptr;
    };
    f << "\nTargets (default 2 passes, 0.2 mm SDF): ";
    for (const auto& [n, target] : {std::pair{200, 1.0}, std::pair{800, 4.0}}) {
      if (const Row* r = find(n, 2, 0.2)) {
        f << fmt::format(
            "{} segments p99 {:.3f} ms (CPU {:.3f} ms) vs {:.0f} ms: {}. ", n, r->p99_ms, r->cpu_p99_ms, target,
            r->p99_ms <= target ? "met" : (r->cpu_p99_ms <= target ? "met in CPU time, not wall" : "missed"));
      }
    }
    // what the table says about convergence, computed from it
    f << "\n\nSettings whose tip did not end in the LAD: ";
    int off = 0;
    for (const Row& r : rows) {
      if (r.final_branch == "LAD") continue;
      f << fmt::format("{}{}/{}/{} ({})", off++ ? ", " : "", r.s.segments, r.s.passes, r.s.spacing_mm, r.final_branch);
    }
    f << (off ? "." : "none.") << " Settings with a node more than the 0.05 mm wall margin outside the lumen: ";
    int outside = 0;
    for (const Row& r : rows) {
      if (r.max_penetration_mm <= 0.05) continue;
      f << fmt::format("{}{}/{}/{} ({:.2f} mm)", outside++ ? ", " : "", r.s.segments, r.s.passes, r.s.spacing_mm,
                       r.max_penetration_mm);
    }
    f << (outside ? "." : "none.") << " (segments/passes/SDF mm)\n\n";
    f << "Convergence in the segment count. The shear limit beta is a curvature (degrees per millimetre), so a "
         "joint's cone is beta times the link length; but a wall or friction correction of depth d at one node "
         "kinks its joint by about d / h. With a cone of beta h the admissible kink shrinks as h^2 while the kinks "
         "grow as 1/h, and the final limit sweep (forward from the catheter, at most beta h per joint) straightens "
         "each kink by swinging the wire beyond it back into the wall by roughly (d/h)^2 / (2 beta): tenths of a "
         "millimetre at 800 segments, where 200 segments (1.5 mm links) never reach their limits. beta is now "
         "resolved over at least 1.5 mm of wire (link_spec.cc, kShearLengthM): the default 200-segment wire and "
         "coarser ones are unchanged; finer wires keep 1.5 mm joint cones. Trade-off: below 1.5 mm the hard limit "
         "no longer bounds the curvature over every stretch (four 0.375 mm links may each turn the 1.5 mm cone); "
         "the bending passes, not the limit, keep a fine wire smooth, and a limit over a window of links would be "
         "the stricter fix. 50 segments (6 mm links in a 2 mm LM) are too coarse to enter the coronaries at all; "
         "1 pass at 200 segments leaves nodes up to 0.7 mm outside (the passes, not the limits, bring it back).\n";
    f << "\nPlot: `guidewire.png` (tip error vs median ms per step), drawn by `scripts/plot_bench.py`.\n";
  }
  if (o.plot)
    o.plot = run_plot_script(
        "guidewire", fmt::format("scripts/plot_bench.py {}/guidewire.json {}/guidewire.png", o.out_dir, o.out_dir));
  std::printf("guidewire: wrote %s/guidewire.md, .json%s\n", o.out_dir.c_str(), o.plot ? ", .png" : "");
  return 0;
}

const bool registered =
    add("guidewire", "chain-mail wire: ms per step and tip error vs segments x passes x SDF spacing", run_bench);

}  // namespace
}  // namespace pcisim::bench
