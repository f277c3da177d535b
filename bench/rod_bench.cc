// pcisim-bench rod: what the Cosserat rod's accuracy costs in time (issue #15), against the exact
// elastica (physics/rod/elastica.h: an analytic reference, not the rod at a finer setting). The
// unit cantilever (physics/rod/unit_cantilever.h) under a tip load (alpha = P L^2 / EI) or its own
// weight (w = q L^3 / EI) is stepped at 30 Hz with damping until it rests; its tip deflection is
// compared with the elastica's, and with the static equilibrium of the same discrete rod (Newton,
// rod_statics.h: what the sweeps would reach converged). Sweeps segments x (substeps x sweeps);
// then the time per 30 Hz step of a 300 mm wire at 1 mm segments (the speed target:
// <= 3 ms at p99 with contact and friction; here without them, an upper bound on what is left).
//
//   pcisim-bench rod [--quick] [--no-plot] [--out DIR]          the sweep: rod.md, rod.json, rod.png
//   pcisim-bench rod --case cantilever_tip|cantilever_weight --load X --segments N
//                    [--substeps S] [--iterations I] [--model rod|chain_mail]   one run, one JSON line
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench/bench_options.h"
#include "bench/bench_registry.h"
#include "bench/bench_stats.h"
#include "bench/machine_info.h"
#include "bench/trainee_session.h"
#include "physics/rod/cosserat_rod.h"
#include "physics/rod/elastica.h"
#include "physics/rod/rod_statics.h"
#include "physics/rod/unit_cantilever.h"
#include "physics/world.h"
#include "physics/guidewire/rod_wire.h"

namespace pcisim::bench {
namespace {

using physics::rod::CosseratRod;
using physics::rod::CosseratRodParams;
using physics::rod::RodSolver;

const char* solver_name(RodSolver s) {
  return s == RodSolver::kDirect ? "direct" : "gauss_seidel";
}

constexpr double kDt = 1.0 / 30.0;  // the physics thread's step

struct Run {
  std::string kind;  // cantilever_tip | cantilever_weight
  double load = 0;
  int segments = 0, substeps = 0, iterations = 0;
  RodSolver solver = RodSolver::kGaussSeidel;
  double exact_dv = 0, rod_dv = 0, static_dv = 0;
  double error_pct = 0, static_error_pct = 0;  // against the elastica
  double ms_p50 = 0, ms_p99 = 0;               // per 30 Hz step
  double rest_s = 0;                           // simulated time to rest
  bool at_rest = false;
};

void load(CosseratRod& rod, const std::string& kind, double value) {
  if (kind == "cantilever_tip") {
    rod.set_node_force_n(rod.segment_count(), Eigen::Vector3d(0, -value, 0));
  } else {
    rod.set_gravity_m_per_s2(Eigen::Vector3d(0, -value, 0));  // mu = 1 kg/m, L = 1 m, EI = 1: w = g
  }
}

double exact_dv(const std::string& kind, double value) {
  return kind == "cantilever_tip" ? physics::rod::cantilever_tip_load(value).dv_over_l
                                  : physics::rod::cantilever_self_weight(value).dv_over_l;
}

Run run_one(const std::string& kind, double value, int segments, RodSolver solver, int substeps, int iterations) {
  Run r{kind, value, segments, substeps, iterations, solver};
  CosseratRodParams p = physics::rod::unit_cantilever(segments);
  p.solver = solver;
  p.substeps = substeps;
  p.iterations = iterations;
  p.damping_per_s = 5.0;
  CosseratRod rod = physics::rod::make_unit_cantilever(p);
  load(rod, kind, value);
  // stepped until the tip rests (speed under 1e-5 m/s after the first second), at most 30 s
  std::vector<double> ms;
  for (int step = 0; step < static_cast<int>(30.0 / kDt); ++step) {
    const auto t0 = std::chrono::steady_clock::now();
    rod.step(kDt);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (step * kDt > 1.0 && rod.max_speed_m_per_s() < 1e-5) {
      r.at_rest = true;
      break;
    }
  }
  r.rest_s = ms.size() * kDt;
  r.ms_p50 = percentile(ms, 0.5);
  r.ms_p99 = percentile(ms, 0.99);
  r.exact_dv = exact_dv(kind, value);
  r.rod_dv = physics::rod::cantilever_tip(rod).dv_over_l;
  r.error_pct = 100.0 * (r.rod_dv - r.exact_dv) / r.exact_dv;
  CosseratRod still = physics::rod::make_unit_cantilever(physics::rod::unit_cantilever(segments));
  load(still, kind, value);
  physics::rod::solve_static(still);
  r.static_dv = physics::rod::cantilever_tip(still).dv_over_l;
  r.static_error_pct = 100.0 * (r.static_dv - r.exact_dv) / r.exact_dv;
  return r;
}

std::string json_of(const Run& r) {
  return fmt::format(
      "{{\"model\": \"rod\", \"solver\": \"{}\", \"case\": \"{}\", \"load\": {}, \"segments\": {}, \"substeps\": {}, "
      "\"iterations\": {}, "
      "\"exact_dv_over_l\": {:.8f}, \"dv_over_l\": {:.8f}, \"error_pct\": {:.4f}, \"static_dv_over_l\": {:.8f}, "
      "\"static_error_pct\": {:.4f}, \"ms_p50\": {:.4f}, \"ms_p99\": {:.4f}, \"at_rest\": {}, \"rest_s\": {:.2f}}}",
      solver_name(r.solver), r.kind, r.load, r.segments, r.substeps, r.iterations, r.exact_dv, r.rod_dv, r.error_pct,
      r.static_dv, r.static_error_pct, r.ms_p50, r.ms_p99, r.at_rest ? "true" : "false", r.rest_s);
}

// the rod in the scenes' world: the default scene's wire as guidewire.model rod (300 mm, 1 mm
// segments), the lumen's SDF contact and friction, the trainee's script down the LAD (insert,
// turn, advance 50 mm, pull back), every World::step timed
struct WorldTiming {
  int substeps;
  double p50, p99, max_ms;
  std::string tip;
};

WorldTiming time_world(int substeps) {
  physics::WorldSpec spec;
  spec.step_s = kDt;
  spec.anatomy.seed = 1;
  spec.guidewire = physics::GuidewireParams{};
  spec.guidewire->model = physics::GuidewireModel::kRod;
  spec.guidewire->segment_count = 300;
  spec.guidewire->rod_substeps = substeps;
  spec.vessel_contact = physics::VesselContactParams{};
  spec.friction = physics::FrictionParams{};
  physics::World world(spec);
  std::vector<double> ms;
  for (double t = 0.0; t <= kSessionS; t += kDt) {
    const auto t0 = std::chrono::steady_clock::now();
    world.step(session_at(t));
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  physics::WorldSnapshot snap;
  world.write_snapshot(snap);
  return {substeps, percentile(ms, 0.5), percentile(ms, 0.99), *std::max_element(ms.begin(), ms.end()),
          world.vessel_tree().branches[snap.tip_branch].name};
}

constexpr const char* kUsage =
    "pcisim-bench rod [--quick] [--no-plot] [--out DIR]\n"
    "  the Cosserat rod's tip deflection against the exact elastica, swept over segments and\n"
    "  substeps x sweeps, with the time per 30 Hz step; rod.md, rod.json (and rod.png) in DIR\n"
    "pcisim-bench rod --case cantilever_tip|cantilever_weight --load X --segments N [--substeps S]\n"
    "                 [--iterations I] [--solver gauss_seidel|direct] [--model rod|chain_mail]\n"
    "  one run, one JSON line on stdout. The chain-mail wire has no load response (no gravity, no\n"
    "  tip force): --model chain_mail says so and exits 3\n"
    "pcisim-bench rod --world SUBSTEPS\n"
    "  the rod in the default scene's world on the trainee's script, every step timed; one JSON line\n";

// one run from the command line; -1 when the arguments are the sweep's
int single(const std::vector<std::string>& args) {
  if (args.size() == 2 && args[0] == "--world") {
    const int substeps = std::atoi(args[1].c_str());
    if (substeps < 1 || substeps > 256) {
      std::fprintf(stderr, "pcisim-bench rod: --world takes substeps in [1, 256], got '%s'\n", args[1].c_str());
      return 2;
    }
    const WorldTiming t = time_world(substeps);
    std::printf("{\"substeps\": %d, \"ms_p50\": %.4f, \"ms_p99\": %.4f, \"ms_max\": %.4f, \"tip_branch\": \"%s\"}\n",
                t.substeps, t.p50, t.p99, t.max_ms, t.tip.c_str());
    return 0;
  }
  std::string kind, model = "rod", solver = "gauss_seidel";
  double value = NAN;
  int segments = 50, substeps = 10, iterations = 4;
  bool any = false;
  for (size_t i = 0; i + 1 < args.size(); i += 2) {
    const std::string& k = args[i];
    const std::string& v = args[i + 1];
    if (k == "--case") {
      kind = v;
    } else if (k == "--load") {
      value = std::atof(v.c_str());
    } else if (k == "--segments") {
      segments = std::atoi(v.c_str());
    } else if (k == "--substeps") {
      substeps = std::atoi(v.c_str());
    } else if (k == "--iterations") {
      iterations = std::atoi(v.c_str());
    } else if (k == "--model") {
      model = v;
    } else if (k == "--solver") {
      solver = v;
    } else {
      continue;
    }
    any = true;
  }
  if (!any) return -1;
  if (model == "chain_mail") {
    std::fprintf(stderr,
                 "pcisim-bench rod: the chain-mail wire has no response to a load (no gravity, no tip force), so no "
                 "cantilever answer (issue #15)\n");
    return 3;
  }
  if (model != "rod" || (solver != "gauss_seidel" && solver != "direct") ||
      (kind != "cantilever_tip" && kind != "cantilever_weight") || !(value >= 0 && value <= 100) || segments < 1 ||
      segments > 2000 || substeps < 1 || iterations < 1) {
    std::fprintf(stderr, "pcisim-bench rod: bad arguments\n%s", kUsage);
    return 2;
  }
  std::printf("%s\n",
              json_of(run_one(kind, value, segments, solver == "direct" ? RodSolver::kDirect : RodSolver::kGaussSeidel,
                              substeps, iterations))
                  .c_str());
  return 0;
}

int run(const std::vector<std::string>& args) {
  if (const int rc = single(args); rc >= 0) return rc;
  BenchOptions bo;
  if (const int rc = parse_bench_options(args, "rod", kUsage, &bo); rc >= 0) return rc;

  struct Solver {
    RodSolver solver;
    int substeps, iterations;
  };
  constexpr RodSolver gs = RodSolver::kGaussSeidel, direct = RodSolver::kDirect;
  const std::vector<int> segments = bo.quick ? std::vector<int>{10, 50} : std::vector<int>{10, 20, 50, 100};
  const std::vector<Solver> solvers =
      bo.quick ? std::vector<Solver>{{gs, 10, 4}, {direct, 4, 2}}
               : std::vector<Solver>{{gs, 10, 4}, {gs, 40, 10}, {direct, 2, 1}, {direct, 4, 2}, {direct, 10, 2}};
  const std::vector<std::pair<std::string, double>> cases =
      bo.quick ? std::vector<std::pair<std::string, double>>{{"cantilever_tip", 10}}
               : std::vector<std::pair<std::string, double>>{
                     {"cantilever_tip", 1}, {"cantilever_tip", 10}, {"cantilever_weight", 10}};
  std::vector<Run> runs;
  for (const auto& [kind, value] : cases)
    for (int n : segments)
      for (const Solver& s : solvers) {
        runs.push_back(run_one(kind, value, n, s.solver, s.substeps, s.iterations));
        const Run& r = runs.back();
        std::printf("%-17s %5.1f  %3d segments  %-12s %2d x %2d: %+9.3f %% (static %+.4f %%)  %.3f / %.3f ms%s\n",
                    kind.c_str(), value, n, solver_name(s.solver), s.substeps, s.iterations, r.error_pct,
                    r.static_error_pct, r.ms_p50, r.ms_p99, r.at_rest ? "" : "  (not at rest after 30 s)");
        std::fflush(stdout);
      }

  // the wire of the scenes: 300 mm at 1 mm segments, the default stiffness, gravity, 300 steps
  struct Timing {
    Solver s;
    double p50, p99;
  };
  std::vector<Timing> timings;
  for (const Solver& s : solvers) {
    CosseratRodParams p;
    p.segments = 300;
    p.solver = s.solver;
    p.substeps = s.substeps;
    p.iterations = s.iterations;
    p.gravity_m_per_s2 = Eigen::Vector3d(0, 0, -9.81);
    CosseratRod rod(p);
    std::vector<double> ms;
    for (int step = 0; step < (bo.quick ? 60 : 300); ++step) {
      const auto t0 = std::chrono::steady_clock::now();
      rod.step(kDt);
      ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    timings.push_back({s, percentile(ms, 0.5), percentile(ms, 0.99)});
    std::printf("300 mm wire, 300 segments, %-12s %2d x %2d: %.2f / %.2f ms per step\n", solver_name(s.solver),
                s.substeps, s.iterations, timings.back().p50, timings.back().p99);
  }

  std::vector<WorldTiming> world_timings;
  for (int substeps : bo.quick ? std::vector<int>{8} : std::vector<int>{4, 8, 16}) {
    world_timings.push_back(time_world(substeps));
    std::printf("rod in the world, %2d substeps: %.2f / %.2f ms per step (max %.2f), tip in %s\n", substeps,
                world_timings.back().p50, world_timings.back().p99, world_timings.back().max_ms,
                world_timings.back().tip.c_str());
  }

  // the beat acting on the rod (issue #15 item 4): the same script in the beating scene (heart,
  // vessels riding it, pulsatile blood), then the wire held for two cycles; the rod living in the
  // moving world (beat_coupling contact) against the rest-frame solution carried by the skin
  // (kinematic): step cost, the guidewire effect's cost, and the held tip's excursion and the
  // distance between the two schemes' tips over the held cycles
  struct BeatRun {
    const char* coupling;
    double p50, p99, wire_p50, wire_p99, excursion_mm;
    std::vector<Eigen::Vector3d> held_tip_m;
  };
  std::vector<BeatRun> beat_runs;
  for (const auto coupling : {physics::BeatCoupling::kContact, physics::BeatCoupling::kKinematic}) {
    physics::WorldSpec spec;
    spec.step_s = kDt;
    spec.anatomy.seed = 1;
    spec.heart_beat = physics::HeartBeatParams{};
    spec.vessel_motion = physics::VesselMotionParams{};
    spec.blood_flow = physics::BloodFlowParams{};
    spec.guidewire = physics::GuidewireParams{};
    spec.guidewire->model = physics::GuidewireModel::kRod;
    spec.guidewire->segment_count = 300;
    spec.guidewire->beat_coupling = coupling;
    spec.vessel_contact = physics::VesselContactParams{};
    spec.friction = physics::FrictionParams{};
    physics::World world(spec);
    BeatRun r{coupling == physics::BeatCoupling::kContact ? "contact" : "kinematic", 0, 0, 0, 0, 0, {}};
    std::vector<double> ms, wire_ms;
    const double held_s = 2.0 * 60.0 / spec.heart_beat->rate_bpm;
    physics::WorldSnapshot snap;
    for (double t = 0.0; t <= kSessionS + held_s; t += kDt) {
      const auto t0 = std::chrono::steady_clock::now();
      world.step(session_at(std::min(t, kSessionS)));
      ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      for (const auto& c : world.effect_costs())
        if (c.name == "guidewire") wire_ms.push_back(c.last_step_ms);
      if (t > kSessionS) {
        world.write_snapshot(snap);
        r.held_tip_m.push_back(snap.tip_m);
      }
    }
    r.p50 = percentile(ms, 0.5);
    r.p99 = percentile(ms, 0.99);
    r.wire_p50 = percentile(wire_ms, 0.5);
    r.wire_p99 = percentile(wire_ms, 0.99);
    for (const auto& a : r.held_tip_m)
      for (const auto& b : r.held_tip_m) r.excursion_mm = std::max(r.excursion_mm, 1e3 * (a - b).norm());
    std::printf("beating scene, rod %s: step %.2f / %.2f ms, guidewire %.2f / %.2f ms, held tip excursion %.2f mm\n",
                r.coupling, r.p50, r.p99, r.wire_p50, r.wire_p99, r.excursion_mm);
    beat_runs.push_back(std::move(r));
  }
  double beat_rms_mm = 0.0, beat_max_mm = 0.0;
  {
    const auto& a = beat_runs[0].held_tip_m;
    const auto& b = beat_runs[1].held_tip_m;
    const size_t m = std::min(a.size(), b.size());
    for (size_t k = 0; k < m; ++k) {
      const double d = 1e3 * (a[k] - b[k]).norm();
      beat_rms_mm += d * d;
      beat_max_mm = std::max(beat_max_mm, d);
    }
    beat_rms_mm = m ? std::sqrt(beat_rms_mm / m) : 0.0;
  }

  std::filesystem::create_directories(bo.out_dir);
  const std::string md_path = bo.out_dir + "/rod.md", json_path = bo.out_dir + "/rod.json";
  std::ofstream md(md_path), js(json_path);
  md << "# Cosserat rod: accuracy against time\n\n"
     << "Generated by `pcisim-bench rod" << (bo.quick ? " --quick" : "") << "` (bench/rod_bench.cc); " << machine_info()
     << ".\n\n"
     << "The XPBD Cosserat rod (physics/rod/cosserat_rod.h, docs/guidewire.md), each substep solved by "
        "Gauss-Seidel sweeps or by the direct solve along the chain (block_tridiagonal.h; iterations are then "
        "Newton iterations), on the unit cantilever "
        "(physics/rod/unit_cantilever.h: L = 1 m, EI = 1 N m², clamped along +x), loaded at its tip (alpha = P L² / "
        "EI) or by its own weight (w = q L³ / EI), stepped at 30 Hz with damping 5/s until its speed is under "
        "1e-5 m/s (at most 30 s). Error: the tip's deflection against the **exact elastica** (shooting to ~1e-8, "
        "physics/rod/elastica.h). 'static': the same discrete rod's equilibrium by Newton's method "
        "(rod_statics.h), what the sweeps reach when they converge: the discretisation's own error. ms: wall time "
        "per 30 Hz step (median / p99 over the steps to rest), one thread.\n\n"
     << "| case | load | segments | solver | substeps x iterations | error % | static error % | ms p50 / p99 | at "
        "rest |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  for (const Run& r : runs) {
    md << fmt::format("| {} | {:g} | {} | {} | {} x {} | {:+.3f} | {:+.4f} | {:.3f} / {:.3f} | {} |\n", r.kind, r.load,
                      r.segments, solver_name(r.solver), r.substeps, r.iterations, r.error_pct, r.static_error_pct,
                      r.ms_p50, r.ms_p99, r.at_rest ? fmt::format("{:.1f} s", r.rest_s) : "no (30 s)");
  }
  md << "\n## A 300 mm wire at 1 mm segments in free space (the default wire's stiffness, gravity; no contact)\n\n"
     << "Issue #15's speed target: <= 3 ms per 30 Hz step at p99 *with* contact and friction.\n\n"
     << "| solver | substeps x iterations | ms p50 | ms p99 | target |\n|---|---|---|---|---|\n";
  for (const Timing& t : timings)
    md << fmt::format("| {} | {} x {} | {:.2f} | {:.2f} | {} |\n", solver_name(t.s.solver), t.s.substeps,
                      t.s.iterations, t.p50, t.p99, t.p99 <= 3.0 ? "met (before contact)" : "**missed**");
  md << "\n## The rod in the world: contact and friction (the issue's speed target)\n\n"
     << "The default scene's wire as `guidewire.model` rod: 300 mm at 1 mm segments, one direct solve per "
        "substep, wall contact with the lumen's SDF (0.2 mm) and Coulomb friction inside the substeps; the "
        "trainee's script (insert 8 mm, turn 90 degrees, advance 50 mm, pull back 5 mm; 585 steps), the whole "
        "World::step timed. Target: <= 3 ms per 30 Hz step at p99.\n\n"
     << "| substeps | ms p50 | ms p99 | ms max | tip ends in | target |\n|---|---|---|---|---|---|\n";
  for (const WorldTiming& t : world_timings)
    md << fmt::format("| {} | {:.2f} | {:.2f} | {:.2f} | {} | {} |\n", t.substeps, t.p50, t.p99, t.max_ms, t.tip,
                      t.p99 <= 3.0 ? "met" : "**missed**");
  md << "\n## The beat acting on the rod (`guidewire.beat_coupling`)\n\n"
     << "The same script in the beating scene (heart_beat, vessel_motion, blood_flow, contact, friction; 72 bpm), "
        "then the wire held for two cycles. `contact`: the rod lives in the moving world and the lumen's wall "
        "pushes it (the rod scene's default); `kinematic`: it is solved in the vessels' rest frame and carried into "
        "the world by the vessels' skin. Step: the whole World::step (heart, skin, blood, wire); guidewire: that "
        "effect alone (the rod, its contact and friction, and for `contact` the nodes' rest points).\n\n"
     << "| coupling | step ms p50 | step ms p99 | guidewire ms p50 | guidewire ms p99 | held tip excursion mm |\n"
     << "|---|---|---|---|---|---|\n";
  for (const BeatRun& r : beat_runs)
    md << fmt::format("| {} | {:.2f} | {:.2f} | {:.2f} | {:.2f} | {:.2f} |\n", r.coupling, r.p50, r.p99, r.wire_p50,
                      r.wire_p99, r.excursion_mm);
  md << fmt::format(
      "\nThe two schemes' tips over the held cycles differ by {:.2f} mm rms, {:.2f} mm at most (world frame, same "
      "step).\n",
      beat_rms_mm, beat_max_mm);
  js << "[\n";
  for (size_t i = 0; i < runs.size(); ++i) js << "  " << json_of(runs[i]) << (i + 1 < runs.size() ? ",\n" : "\n");
  js << "]\n";
  md.close();
  js.close();
  if (bo.plot && std::filesystem::exists("docs/benchmarks/rod.py")) {
    if (run_plot_script("rod", "docs/benchmarks/rod.py " + json_path + " " + bo.out_dir + "/rod.png"))
      std::ofstream(md_path, std::ios::app) << "\n![error against time](rod.png)\n";
  }
  std::printf("wrote %s and %s\n", md_path.c_str(), json_path.c_str());
  return 0;
}

const bool registered = add("rod", "Cosserat rod: tip deflection against the exact elastica, and its cost", run);

}  // namespace
}  // namespace pcisim::bench
