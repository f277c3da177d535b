// pcisim-bench soft-tissue: what the soft tissue's accuracy costs in time (issue #16). The kidney
// through the calibration protocol (physics/soft_tissue/calibration.h: warm-up, the probe pressed
// in stages) at particle radius x substeps x iterations x solver (Gauss-Seidel, Jacobi + SOR w),
// each run's fiducial error against a static neo-Hookean FEM of the same organ (an independent
// method with known material, not a finer PBD run) and its ms per step. Writes soft-tissue.md,
// soft-tissue.json and (with python3-matplotlib) soft-tissue.png into docs/benchmarks/ or --out.
#include <fmt/format.h>

#include <cstdio>
#include <fstream>

#include "anatomy/organ/kidney_phantom.h"
#include "bench_options.h"
#include "kidney_tetgen_mesh.h"
#include "bench_registry.h"
#include "bench_stats.h"
#include "machine_info.h"
#include "physics/soft_tissue/calibration.h"

namespace pcisim::bench {
namespace {

namespace st = physics::soft_tissue;

const char* kUsage =
    "usage: pcisim-bench soft-tissue [--quick] [--no-plot] [--out DIR]\n"
    "  the kidney pressed in stages (3, 6, 9, 12 mm) at particle radius x substeps x iterations x solver;\n"
    "  fiducial error against a neo-Hookean FEM (E 5 kPa, nu 0.45, 5 mm TetGen tets) and ms per step.\n"
    "  --quick: an 8 mm reference and fewer settings. Writes soft-tissue.md, .json, .png.\n";

struct Row {
  double radius_mm;
  int substeps, iterations;
  std::string solver;
  double sor_w;
  st::PbdRun run;
};

int run(const std::vector<std::string>& args) {
  BenchOptions o;
  if (const int rc = parse_bench_options(args, "soft-tissue", kUsage, &o); rc >= 0) return rc;
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  anatomy::KidneySpec k;
  k.ct_spacing_mm = 4.0;  // the CT is not used
  st::CalibrationSetup setup = st::kidney_calibration_setup(anatomy::kidney_organ(anatomy::make_kidney_phantom(k)));
  // pcisim-calibrate's reference: TetGen's body-fitted tets (5 mm: within ~0.2 mm of a 6 mm one)
  setup.fem_spacing_m = o.quick ? 8e-3 : 5e-3;
  std::printf("soft-tissue: the reference (%.0f mm tets) ...\n", setup.fem_spacing_m * 1e3);
  const st::FemReference ref = st::solve_fem_reference(setup, kidney_tetgen_mesh(k, setup.fem_spacing_m));
  std::printf("  %d nodes, %.1f s\n", ref.nodes, ref.seconds);

  // the cluster compliance of each radius's optimum for the paper's model, shape matching alone
  // (docs/benchmarks/soft-tissue-calibration.md; the scene's optimum adds the clusters' volume)
  const std::vector<std::pair<double, double>> radii =
      o.quick ? std::vector<std::pair<double, double>>{{5.0, 3e-5}}
              : std::vector<std::pair<double, double>>{{3.3, 1e-5}, {5.0, 3e-5}};
  const std::vector<int> substeps = o.quick ? std::vector<int>{3} : std::vector<int>{1, 3};
  const std::vector<int> iterations = {3, 9};
  const std::vector<std::pair<std::string, double>> solvers = {{"gauss_seidel", 1.0}, {"jacobi", 1.0}, {"jacobi", 1.5}};
  std::vector<Row> rows;
  for (const auto& [r_mm, compliance] : radii)
    for (int sub : substeps)
      for (int it : iterations)
        for (const auto& [solver, w] : solvers) {
          st::SoftTissueSpec spec;
          spec.model.particle_radius_m = r_mm * 1e-3;
          spec.params.cluster_compliance_s2 = compliance;
          spec.params.substeps = sub;
          spec.params.iterations = it;
          spec.params.solver =
              solver == "jacobi" ? physics::pbd::SolverKind::kJacobi : physics::pbd::SolverKind::kGaussSeidel;
          spec.params.sor_w = w;
          Row row{r_mm, sub, it, solver, w, st::run_pbd_protocol(setup, spec, ref)};
          std::printf("  r %.1f mm, %d x %d, %s w %.1f: %.2f mm mean over the stages, step p50 %.1f / p99 %.1f ms\n",
                      r_mm, sub, it, solver.c_str(), w, row.run.mean_over_stages_m * 1e3,
                      percentile(row.run.step_ms, 0.5), percentile(row.run.step_ms, 0.99));
          rows.push_back(std::move(row));
        }

  std::filesystem::create_directories(o.out_dir);
  {
    std::ofstream j(o.out_dir + "/soft-tissue.json");
    j << "[\n";
    for (size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      j << fmt::format(
          "  {{\"radius_mm\": {}, \"substeps\": {}, \"iterations\": {}, \"solver\": \"{}\", \"sor_w\": {}, "
          "\"mean_error_mm\": {:.4f}, \"last_stage_mean_mm\": {:.4f}, \"last_stage_max_mm\": {:.4f}, "
          "\"step_ms_p50\": {:.3f}, \"step_ms_p99\": {:.3f}}}{}\n",
          r.radius_mm, r.substeps, r.iterations, r.solver, r.sor_w, r.run.mean_over_stages_m * 1e3,
          r.run.stages.back().mean_m * 1e3, r.run.stages.back().max_m * 1e3, percentile(r.run.step_ms, 0.5),
          percentile(r.run.step_ms, 0.99), i + 1 < rows.size() ? "," : "");
    }
    j << "]\n";
  }
  const bool plotted =
      o.plot && run_plot_script("soft-tissue", "docs/benchmarks/soft-tissue.py " + o.out_dir + "/soft-tissue.json " +
                                                   o.out_dir + "/soft-tissue.png");
  std::ofstream md(o.out_dir + "/soft-tissue.md");
  md << "# Soft tissue: accuracy against time (generated by `pcisim-bench soft-tissue`; do not edit)\n\n"
     << "Machine: " << machine_info() << "\n\n"
     << fmt::format(
            "The kidney through the calibration protocol ({} warm-up steps, the probe moved over {} steps of 1/60 s "
            "to each of 3, 6, 9 and 12 mm into the skin; support glued, probe frictionless), each setting's "
            "fiducial error against a static neo-Hookean FEM of the same organ (E 5 kPa, nu 0.45, {:.0f} mm "
            "linear tets from TetGen, body-fitted, {} nodes; an independent method, not a finer PBD run). Error: the "
            "beads' mean distance "
            "from the reference's, averaged over the four pressed stages; the last stage's mean and max beside it. "
            "Time: wall ms per 1/60 s step after the warm-up (p50 / p99), one process on this 2-core machine.\n\n",
            setup.warmup_steps, setup.steps_per_stage, setup.fem_spacing_m * 1e3, ref.nodes)
     << "| radius (mm) | substeps x iterations | solver | mean error (mm) | 12 mm stage mean / max (mm) | step p50 "
        "(ms) | step p99 (ms) |\n|---|---|---|---|---|---|---|\n";
  for (const Row& r : rows)
    md << fmt::format("| {} | {} x {} | {}{} | {:.2f} | {:.2f} / {:.2f} | {:.1f} | {:.1f} |\n", r.radius_mm, r.substeps,
                      r.iterations, r.solver, r.solver == "jacobi" ? fmt::format(" w {}", r.sor_w) : "",
                      r.run.mean_over_stages_m * 1e3, r.run.stages.back().mean_m * 1e3, r.run.stages.back().max_m * 1e3,
                      percentile(r.run.step_ms, 0.5), percentile(r.run.step_ms, 0.99));
  if (plotted) md << "\n![fiducial error against ms per step](soft-tissue.png)\n";
  md << "\nTarget (issue #16): one step at the paper's resolutions (2.2-3.3 mm) <= 6 ms at p99 on 2 cores. "
     << "See the 3.3 mm rows: met only where their p99 is <= 6 ms.\n";
  std::printf("soft-tissue: wrote %s/soft-tissue.md, .json%s\n", o.out_dir.c_str(), plotted ? ", .png" : "");
  return 0;
}

const bool registered = add("soft-tissue", "soft tissue: fiducial error against a neo-Hookean FEM vs ms per step", run);

}  // namespace
}  // namespace pcisim::bench
