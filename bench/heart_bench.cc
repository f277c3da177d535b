// pcisim-bench heart: what PBD accuracy costs on the beating heart (physics/heart): the template
// heart with its ventricles driven by the synthetic motion sequence at 72 bpm and the coronary
// tree skinned to its epicardium. Sweeps iterations x substeps x solver (Gauss-Seidel, Jacobi with
// SOR w in {1, 1.5, 1.9}) x cluster size (the global cluster alone, or with local clusters) at the
// scene rate (30 Hz). Per setting: mean and max distance of every free particle from a converged
// reference run (Gauss-Seidel, many substeps and iterations) at every step, the epicardial tree's
// drift from the reference tree (max over centerline points and steps), and median / p99 wall and
// CPU ms per step. Writes heart.md, heart.json and (with /usr/bin/python3 + matplotlib) heart.png
// into docs/benchmarks/ or --out DIR. The scene-level figures (whole default scene, one cycle,
// moving SDF) are `pcisim-bench heart-scene`.
#include <fmt/format.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "bench/bench_options.h"
#include "bench/bench_registry.h"
#include "bench/bench_stats.h"
#include "bench/machine_info.h"
#include "physics/heart/beating_heart.h"
#include "physics/motion/vessel_skin.h"
#include "physics/pbd/pbd_cuda_solver.h"
#include "anatomy/phantom/coronary_phantom.h"

namespace pcisim::bench {
namespace {

using namespace pcisim::physics::pbd;
using pcisim::physics::BeatingHeart;
using pcisim::physics::HeartBeatParams;
using pcisim::physics::VesselSkin;

constexpr double kDtS = 1.0 / 30.0;
constexpr double kRateBpm = 72.0;

struct Solver {
  SolverKind kind;
  double w;
  std::string name() const {
    if (kind == SolverKind::kGaussSeidel) return "GS";
    if (kind == SolverKind::kJacobiCuda) return fmt::format("Jacobi CUDA w={}", w);
    return fmt::format("Jacobi w={}", w);
  }
};

struct Row {
  double cluster_mm = 0;
  int clusters = 0;
  Solver solver{SolverKind::kGaussSeidel, 1.0};
  int substeps = 1, iterations = 1;
  double mean_err_mm = 0, max_err_mm = 0, final_mean_err_mm = 0;
  double median_ms = 0, p99_ms = 0, cpu_median_ms = 0, cpu_p99_ms = 0;
  double tree_drift_mm = 0;  // max over centerline points and steps, from the reference's tree
  bool finite = true;
};

// one step's state: free particle positions and the skinned tree's points
struct Frame {
  Eigen::Matrix3Xd particles_m;
  std::vector<Eigen::Vector3d> tree_m;
};

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

HeartBeatParams params_for(double cluster_mm, const Solver& solver, int substeps, int iterations) {
  HeartBeatParams p;
  p.rate_bpm = kRateBpm;
  p.substeps = substeps;
  p.iterations = iterations;
  p.solver = solver.kind;
  p.sor_w = solver.w;
  p.cluster_size_m = cluster_mm * 1e-3;
  return p;
}

// runs `steps` steps; record gets every step's state (for the reference), or errors are
// measured against ref (when given). The skin is shared: it only maps a heart's positions.
Row run(double cluster_mm, const Solver& solver, int substeps, int iterations, int steps, VesselSkin& skin,
        std::vector<Frame>* record, const std::vector<Frame>* ref) {
  BeatingHeart heart(params_for(cluster_mm, solver, substeps, iterations));
  const auto free = heart.free_particles();
  Row r;
  r.cluster_mm = cluster_mm;
  r.clusters = heart.system().clusters().count();
  r.solver = solver;
  r.substeps = substeps;
  r.iterations = iterations;
  std::vector<double> wall, cpu;
  wall.reserve(steps);
  cpu.reserve(steps);
  double err_sum = 0.0;
  long err_n = 0;
  Eigen::Matrix3Xd x_free(3, static_cast<Eigen::Index>(free.size()));
  for (int k = 1; k <= steps; ++k) {
    const double c0 = thread_cpu_ms();
    const auto t0 = std::chrono::steady_clock::now();
    heart.step(kDtS);
    const auto t1 = std::chrono::steady_clock::now();
    cpu.push_back(thread_cpu_ms() - c0);
    wall.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    for (size_t i = 0; i < free.size(); ++i)
      x_free.col(static_cast<Eigen::Index>(i)) = heart.positions_m().col(free[i]);
    skin.update(heart.positions_m());
    if (record) record->push_back({x_free, {skin.points_m().begin(), skin.points_m().end()}});
    if (ref) {
      const Frame& f = (*ref)[k - 1];
      const Eigen::VectorXd d = (x_free - f.particles_m).colwise().norm();
      err_sum += d.sum();
      err_n += d.size();
      r.max_err_mm = std::max(r.max_err_mm, d.maxCoeff() * 1e3);
      if (k == steps) r.final_mean_err_mm = d.mean() * 1e3;
      for (size_t i = 0; i < f.tree_m.size(); ++i)
        r.tree_drift_mm = std::max(r.tree_drift_mm, (skin.points_m()[i] - f.tree_m[i]).norm() * 1e3);
    }
  }
  r.finite = heart.positions_m().allFinite() && heart.system().quarantined_total() == 0;
  r.mean_err_mm = err_n ? err_sum / err_n * 1e3 : 0.0;
  r.median_ms = percentile(wall, 0.5);
  r.p99_ms = percentile(wall, 0.99);
  r.cpu_median_ms = percentile(cpu, 0.5);
  r.cpu_p99_ms = percentile(cpu, 0.99);
  return r;
}

constexpr const char* kUsage =
    "usage: pcisim-bench heart [--quick] [--out DIR] [--no-plot]\n"
    "  iterations {1,2,4,8,16} x substeps {1,2,4,8} x (GS, Jacobi w 1/1.5/1.9) x clusters (global only,\n"
    "  global + 20 mm local), settings of at most 32 sweeps per step (--quick: iterations {1,4,16} x\n"
    "  substeps {1,4} x (GS, Jacobi w 1.5), global only) on the beating template heart at 72 bpm, 30 Hz,\n"
    "  against a Gauss-Seidel reference with many substeps and iterations; reports particle error,\n"
    "  epicardial tree drift and ms per step\n";

int run_bench(const std::vector<std::string>& args) {
  BenchOptions o;
  if (const int rc = parse_bench_options(args, "heart", kUsage, &o); rc >= 0) return rc;
  std::filesystem::create_directories(o.out_dir);
  const std::vector<int> iterations = o.quick ? std::vector<int>{1, 4, 16} : std::vector<int>{1, 2, 4, 8, 16};
  const std::vector<int> substeps = o.quick ? std::vector<int>{1, 4} : std::vector<int>{1, 2, 4, 8};
  const std::vector<Solver> solvers =
      o.quick ? std::vector<Solver>{{SolverKind::kGaussSeidel, 1.0}, {SolverKind::kJacobi, 1.5}}
              : std::vector<Solver>{{SolverKind::kGaussSeidel, 1.0},
                                    {SolverKind::kJacobi, 1.0},
                                    {SolverKind::kJacobi, 1.5},
                                    {SolverKind::kJacobi, 1.9}};
  // the CUDA Jacobi twin where a GPU is present (compared against the CPU rows of the same w)
  std::vector<Solver> all_solvers = solvers;
  if (pbd_cuda_available()) all_solvers.push_back({SolverKind::kJacobiCuda, 1.5});
  // 0: the heart paper's single global cluster; 20 mm: local clusters as well (soft-tissue paper)
  const std::vector<double> cluster_mm = o.quick ? std::vector<double>{0.0} : std::vector<double>{0.0, 20.0};
  const int steps = o.quick ? 25 : 38;  // one and one and a half beats at 72 bpm
  // substeps dominate the error (see the table), so the reference spends its budget on them
  const int ref_substeps = o.quick ? 64 : 256, ref_iterations = 4;
  const std::string machine = machine_info();
  int particles = 0, driven = 0, springs = 0, bends = 0, free_n = 0;
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({1});
  std::optional<VesselSkin> skin_slot;
  {
    const BeatingHeart h(params_for(0.0, solvers[0], 1, 1));
    particles = h.system().particle_count();
    driven = static_cast<int>(h.driven().size());
    free_n = static_cast<int>(h.free_particles().size());
    springs = static_cast<int>(h.system().distance_constraints().size());
    bends = static_cast<int>(h.system().bending_constraints().size());
    skin_slot.emplace(tree, h.rest_positions_m(), h.epicardium(), physics::VesselMotionParams{});
  }
  VesselSkin& skin = *skin_slot;

  std::vector<Row> rows;
  std::vector<Row> refs;
  for (double cm : cluster_mm) {
    std::vector<Frame> reference;
    reference.reserve(steps);
    Row ref = run(cm, {SolverKind::kGaussSeidel, 1.0}, ref_substeps, ref_iterations, steps, skin, &reference, nullptr);
    // is the reference converged? the same run with half the substeps and half the iterations
    const Row half = run(cm, {SolverKind::kGaussSeidel, 1.0}, ref_substeps / 2, ref_iterations / 2, steps, skin,
                         nullptr, &reference);
    ref.mean_err_mm = half.mean_err_mm;
    ref.max_err_mm = half.max_err_mm;
    ref.tree_drift_mm = half.tree_drift_mm;
    refs.push_back(ref);
    std::printf(
        "heart: cluster %.0f mm (%d clusters): reference GS %dx%d median %.2f ms; half of it differs by mean %.4f max "
        "%.4f mm\n",
        cm, ref.clusters, ref_substeps, ref_iterations, ref.median_ms, half.mean_err_mm, half.max_err_mm);
    for (const Solver& s : all_solvers)
      for (int sub : substeps)
        for (int it : iterations) {
          if (sub * it > 32) continue;  // beyond any real-time budget here
          Row r = run(cm, s, sub, it, steps, skin, nullptr, &reference);
          rows.push_back(r);
          std::printf(
              "heart: %4.0f mm %-12s sub %d it %2d: median %.3f ms p99 %.3f ms  err mean %.3f max %.3f mm  tree %.3f "
              "mm%s\n",
              cm, s.name().c_str(), sub, it, r.median_ms, r.p99_ms, r.mean_err_mm, r.max_err_mm, r.tree_drift_mm,
              r.finite ? "" : "  NON-FINITE");
        }
  }

  // equal cost: sweeps per step = substeps x iterations; does spending them on substeps win?
  struct Pair {
    double cm;
    std::string solver;
    int cost;
    const Row* by_substeps;    // most substeps, fewest iterations
    const Row* by_iterations;  // fewest substeps, most iterations
  };
  std::vector<Pair> pairs;
  for (double cm : cluster_mm)
    for (const Solver& s : all_solvers)
      for (int cost : {4, 8, 16}) {
        const Row *a = nullptr, *b = nullptr;
        for (const Row& r : rows) {
          if (r.cluster_mm != cm || r.solver.name() != s.name() || r.substeps * r.iterations != cost) continue;
          if (!a || r.substeps > a->substeps) a = &r;
          if (!b || r.substeps < b->substeps) b = &r;
        }
        if (a && b && a != b) pairs.push_back({cm, s.name(), cost, a, b});
      }
  int substeps_win = 0;
  for (const Pair& p : pairs) substeps_win += p.by_substeps->mean_err_mm < p.by_iterations->mean_err_mm;

  {
    std::ofstream f(o.out_dir + "/heart.json");
    f << "{\n" << fmt::format("  \"machine\": \"{}\",\n  \"quick\": {},\n", machine, o.quick);
    f << fmt::format(
        "  \"body\": {{\"particles\": {}, \"driven\": {}, \"free\": {}, \"springs\": {}, \"bends\": {}, \"dt_s\": "
        "{:.6f}, "
        "\"steps\": {}, \"rate_bpm\": {}}},\n",
        particles, driven, free_n, springs, bends, kDtS, steps, kRateBpm);
    f << "  \"references\": [";
    for (size_t i = 0; i < refs.size(); ++i)
      f << fmt::format(
          "{}{{\"cluster_mm\": {}, \"clusters\": {}, \"substeps\": {}, \"iterations\": {}, \"median_ms\": {:.3f}, "
          "\"half_mean_err_mm\": {:.5f}, \"half_max_err_mm\": {:.5f}, \"half_tree_drift_mm\": {:.5f}}}",
          i ? ", " : "", refs[i].cluster_mm, refs[i].clusters, ref_substeps, ref_iterations, refs[i].median_ms,
          refs[i].mean_err_mm, refs[i].max_err_mm, refs[i].tree_drift_mm);
    f << "],\n  \"rows\": [\n";
    for (size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      f << fmt::format(
          "    {{\"cluster_mm\": {}, \"clusters\": {}, \"solver\": \"{}\", \"sor_w\": {}, \"substeps\": {}, "
          "\"iterations\": {}, "
          "\"mean_err_mm\": {:.5f}, \"max_err_mm\": {:.5f}, \"final_mean_err_mm\": {:.5f}, \"median_ms\": {:.4f}, "
          "\"p99_ms\": {:.4f}, \"cpu_median_ms\": {:.4f}, \"cpu_p99_ms\": {:.4f}, \"tree_drift_mm\": {:.5f}, "
          "\"finite\": {}}}{}\n",
          r.cluster_mm, r.clusters, r.solver.name(), r.solver.w, r.substeps, r.iterations, r.mean_err_mm, r.max_err_mm,
          r.final_mean_err_mm, r.median_ms, r.p99_ms, r.cpu_median_ms, r.cpu_p99_ms, r.tree_drift_mm, r.finite,
          i + 1 < rows.size() ? "," : "");
    }
    f << "  ]\n}\n";
  }
  {
    std::ofstream f(o.out_dir + "/heart.md");
    f << "# Heart benchmark: PBD accuracy against time on the beating heart\n\n";
    f << fmt::format("Generated by `pcisim-bench heart{}` on {}; single-threaded.\n\n", o.quick ? " --quick" : "",
                     machine);
    f << fmt::format(
        "Body: the template heart (docs/heart.md): {} particles at the TetGen vertices, {} of them driven by the "
        "synthetic motion sequence (the ventricles), {} free (atria, AV plane); {} stretch/twist springs and {} "
        "bending springs that touch a free particle; one global shape-matching cluster, plus local clusters in the "
        "rows with a cluster size; {} bpm, {} steps of 1/30 s from end-diastole (about {:.1f} beats). The coronary "
        "tree (seed 1) is skinned to the epicardium (physics/motion/vessel_skin.h).\n\n",
        particles, driven, free_n, springs, bends, kRateBpm, steps, steps * kDtS * kRateBpm / 60.0);
    f << fmt::format(
        "Reference: Gauss-Seidel, {} substeps x {} iterations, same cluster size. Error: distance of every free "
        "particle from the reference at every step, mean and max over particles and steps (driven particles are "
        "exact in every run); tree drift: the largest distance of any coronary centerline point from where the "
        "reference's heart carries it, over all steps. Times: wall clock of "
        "`BeatingHeart::step` (the PBD step and setting the driven particles' targets; median, p99) and the "
        "thread's CPU time (median, p99). Cost of a setting ~ substeps x "
        "iterations constraint sweeps.\n\n",
        ref_substeps, ref_iterations);
    f << "Reference convergence (the reference run with half its substeps and half its iterations, against it):";
    for (const Row& r : refs)
      f << fmt::format(
          " cluster size {} mm ({} clusters): mean {:.4f} mm, max {:.4f} mm, tree {:.4f} mm, {:.1f} ms per step;",
          r.cluster_mm, r.clusters, r.mean_err_mm, r.max_err_mm, r.tree_drift_mm, r.median_ms);
    f << "\n\n";
    f << "Cluster mm 0: the global cluster only.\n\n";
    f << "| cluster mm | clusters | solver | substeps | iterations | sweeps | mean err mm | max err mm | tree drift mm "
         "| median ms | p99 ms | CPU median ms | CPU p99 ms |\n";
    f << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows)
      f << fmt::format(
          "| {} | {} | {}{} | {} | {} | {} | {:.3f} | {:.3f} | {:.3f} | {:.3f} | {:.3f} | {:.3f} | {:.3f} |\n",
          r.cluster_mm, r.clusters, r.solver.name(), r.finite ? "" : " (quarantined particles)", r.substeps,
          r.iterations, r.substeps * r.iterations, r.mean_err_mm, r.max_err_mm, r.tree_drift_mm, r.median_ms, r.p99_ms,
          r.cpu_median_ms, r.cpu_p99_ms);
    f << "\n## Substeps or iterations at equal cost\n\n";
    f << "Jacobi here is averaged per constraint (the heart's setting, momentum-conserving; docs/pbd.md).\n\n";
    f << "Pairs with the same number of sweeps per step (substeps x iterations), all substeps vs all iterations:\n\n";
    f << "| cluster mm | solver | sweeps | substeps x iterations: mean err mm | ms | vs | mean err mm | ms | better "
         "|\n";
    f << "|---|---|---|---|---|---|---|---|---|\n";
    for (const Pair& p : pairs)
      f << fmt::format("| {} | {} | {} | {}x{}: {:.3f} | {:.3f} | {}x{}: | {:.3f} | {:.3f} | {} |\n", p.cm, p.solver,
                       p.cost, p.by_substeps->substeps, p.by_substeps->iterations, p.by_substeps->mean_err_mm,
                       p.by_substeps->median_ms, p.by_iterations->substeps, p.by_iterations->iterations,
                       p.by_iterations->mean_err_mm, p.by_iterations->median_ms,
                       p.by_substeps->mean_err_mm < p.by_iterations->mean_err_mm ? "substeps" : "iterations");
    f << fmt::format("\nSubsteps gave the smaller error in {} of {} equal-cost pairs.\n", substeps_win, pairs.size());
    f << "\n## Findings (computed from the table)\n\n";
    for (double cm : cluster_mm) {
      for (double budget_ms : {2.0, 5.0, 10.0}) {
        const Row* best = nullptr;
        for (const Row& r : rows)
          if (r.cluster_mm == cm && r.finite && r.median_ms <= budget_ms &&
              (!best || r.mean_err_mm < best->mean_err_mm))
            best = &r;
        if (best)
          f << fmt::format(
              "- {} mm clusters, median step within {} ms: best is {} {}x{} (mean {:.3f} mm, max {:.3f} mm, "
              "tree drift {:.3f} mm, median {:.2f} ms, p99 {:.2f} ms).\n",
              cm, budget_ms, best->solver.name(), best->substeps, best->iterations, best->mean_err_mm, best->max_err_mm,
              best->tree_drift_mm, best->median_ms, best->p99_ms);
      }
    }
    // where iterations beat substeps at equal cost, named
    std::string iteration_wins;
    for (const Pair& p : pairs)
      if (p.by_iterations->mean_err_mm <= p.by_substeps->mean_err_mm)
        iteration_wins += fmt::format("{}{} {}x{} over {}x{} ({} mm clusters)", iteration_wins.empty() ? "" : "; ",
                                      p.solver, p.by_iterations->substeps, p.by_iterations->iterations,
                                      p.by_substeps->substeps, p.by_substeps->iterations, p.cm);
    f << fmt::format("- Iterations beat substeps at equal cost in {} pair(s){}{}.\n", pairs.size() - substeps_win,
                     iteration_wins.empty() ? "" : ": ", iteration_wins);
    // Jacobi rows with one iteration per substep: does w change anything?
    int one_iteration_groups = 0, w_blind = 0;
    for (const Row& a : rows) {
      if (a.solver.kind != SolverKind::kJacobi || a.iterations != 1 || a.solver.w != 1.0) continue;
      ++one_iteration_groups;
      bool same = true;
      for (const Row& b : rows)
        if (b.solver.kind == SolverKind::kJacobi && b.iterations == 1 && b.substeps == a.substeps &&
            b.cluster_mm == a.cluster_mm)
          same = same && b.mean_err_mm == a.mean_err_mm && b.max_err_mm == a.max_err_mm;
      w_blind += same;
    }
    if (one_iteration_groups > 0)
      f << fmt::format(
          "- Jacobi with one iteration per substep: the rows for every w are identical in {} of {} "
          "settings (the last iteration of a substep is never over-relaxed; docs/pbd.md).\n",
          w_blind, one_iteration_groups);
    f << "\nNote: errors close to the reference's own convergence figure above are not resolved; below it the "
         "ranking of settings is noise.\n";
    f << "\nPlot: `heart.png` (mean error vs median ms per step), drawn by `docs/benchmarks/heart.py`.\n";
  }
  if (o.plot) o.plot = run_plot_script("heart", "docs/benchmarks/heart.py " + o.out_dir);
  std::printf("heart: substeps won %d of %zu equal-cost pairs; wrote %s/heart.md, .json%s\n", substeps_win,
              pairs.size(), o.out_dir.c_str(), o.plot ? ", .png" : "");
  return 0;
}

const bool registered =
    add("heart", "beating heart PBD: error and tree drift vs ms over iterations x substeps x solver x cluster size",
        run_bench);

}  // namespace
}  // namespace pcisim::bench
