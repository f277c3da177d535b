// pcisim-calibrate: the soft-tissue paper's calibration (issue #16 item 5) on the procedural
// kidney. For each particle radius, a 1-D exhaustive search of the cluster compliance (our
// stiffness knob: 1/omega^2 of each cluster's pull) minimising the mean fiducial error over the
// probe's deformation stages, against a static neo-Hookean FEM of the same organ under the same
// probe, support and gravity (physics/soft_tissue/calibration.h). Writes a JSON report and a
// Markdown summary in the paper's form (mean / std / max error per stage x radius at each
// radius's optimum, and error against stiffness).
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "anatomy/organ/kidney_phantom.h"
#include "bench/kidney_tetgen_mesh.h"
#include "physics/soft_tissue/calibration.h"
#include "realtime/percentile.h"

namespace st = pcisim::physics::soft_tissue;

int main(int argc, char** argv) {
  CLI::App app{
      "pcisim-calibrate: calibrates the soft tissue's cluster compliance per particle radius against a\n"
      "neo-Hookean FEM of the procedural kidney (the paper's protocol: warm-up, the probe pressed in\n"
      "stages, mean fiducial error per stage; a 1-D exhaustive search). Writes OUT.json and OUT.md."};
  std::vector<double> radii_mm{3.3, 4.0, 5.0};
  std::vector<double> compliances{1e-6, 3e-6, 1e-5, 3e-5, 1e-4, 3e-4, 1e-3};
  double young_kpa = 5.0, poisson = 0.45, fem_mm = 5.0, check_mm = 6.0;
  int seed = 1, warmup = 120, per_stage = 90;
  std::string mesher = "tetgen";
  std::string out = "docs/benchmarks/soft-tissue-calibration";
  app.add_option("--radii-mm", radii_mm, "particle radii to calibrate (the paper: 2.2-3.3 mm)");
  app.add_option("--compliances", compliances, "the cluster compliances searched (s^2; smaller is stiffer)");
  app.add_option("--young-kpa", young_kpa, "the reference's Young's modulus")->check(CLI::Range(0.1, 1000.0));
  app.add_option("--poisson", poisson, "the reference's Poisson's ratio")->check(CLI::Range(0.0, 0.49));
  app.add_option("--fem-mm", fem_mm, "the reference's mesh spacing")->check(CLI::Range(1.0, 10.0));
  app.add_option("--check-mm", check_mm,
                 "a coarser reference whose difference from the fine one estimates the reference's own error "
                 "(0: none)")
      ->check(CLI::Range(0.0, 20.0));
  app.add_option("--mesh", mesher,
                 "the reference's tets: tetgen (body-fitted, the organ's own surface) or voxel (Kuhn tets on "
                 "the voxelised organ, a stair-stepped surface)")
      ->check(CLI::IsMember({"tetgen", "voxel"}));
  app.add_option("--seed", seed, "the kidney phantom's seed");
  app.add_option("--warmup-steps", warmup, "PBD steps before the first stage (the paper: 120)");
  app.add_option("--steps-per-stage", per_stage, "PBD steps the probe takes to each stage (the paper: 90)");
  app.add_option("--out", out, "report path without extension");
  CLI11_PARSE(app, argc, argv);

  pcisim::anatomy::KidneySpec kspec;
  kspec.seed = static_cast<uint64_t>(seed);
  kspec.ct_spacing_mm = 4.0;  // the CT is not used (nor by the reference's surfaces below)
  const pcisim::anatomy::Organ organ = pcisim::anatomy::kidney_organ(pcisim::anatomy::make_kidney_phantom(kspec));
  st::CalibrationSetup setup = st::kidney_calibration_setup(organ);
  setup.young_pa = young_kpa * 1e3;
  setup.poisson = poisson;
  setup.fem_spacing_m = fem_mm * 1e-3;
  setup.warmup_steps = warmup;
  setup.steps_per_stage = per_stage;

  // progress goes out line by line even into a pipe
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  auto mesh_at = [&](double spacing_m) {
    st::CalibrationSetup at = setup;
    at.fem_spacing_m = spacing_m;
    return mesher == "voxel" ? st::voxel_reference_mesh(at) : pcisim::bench::kidney_tetgen_mesh(kspec, spacing_m);
  };
  fmt::print("reference: neo-Hookean FEM, E {} kPa, nu {}, {} tets of {} mm ...\n", young_kpa, poisson, mesher, fem_mm);
  const st::FemReference ref = st::solve_fem_reference(setup, mesh_at(setup.fem_spacing_m));
  fmt::print("  {} nodes, {} tets, {:.1f} s; stages:", ref.nodes, ref.tets, ref.seconds);
  for (size_t k = 0; k < ref.solves.size(); ++k)
    fmt::print(" [{} Newton, residual {:.1e} N{}]", ref.solves[k].newton_iterations, ref.solves[k].residual_n,
               ref.solves[k].converged ? "" : ", NOT converged");
  fmt::print("\n");

  // the reference's own discretisation error, estimated by a coarser mesh (not a bound)
  std::vector<double> check_diff_mm;
  if (check_mm > 0) {
    const st::FemReference c = st::solve_fem_reference(setup, mesh_at(check_mm * 1e-3));
    for (size_t k = 0; k < c.fiducials_m.size(); ++k)
      check_diff_mm.push_back((c.fiducials_m[k] - ref.fiducials_m[k]).colwise().norm().mean() * 1e3);
    fmt::print("  a {} mm reference differs from it by {} mm (mean over the beads, per stage)\n", check_mm,
               fmt::join(check_diff_mm, ", "));
  }

  nlohmann::json report;
  report["reference"] = {{"model", mesher == "tetgen" ? "static neo-Hookean FEM, linear tets (TetGen, body-fitted)"
                                                      : "static neo-Hookean FEM, linear tets on the voxelised organ"},
                         {"mesh", mesher},
                         {"young_kpa", young_kpa},
                         {"poisson", poisson},
                         {"spacing_mm", fem_mm},
                         {"nodes", ref.nodes},
                         {"tets", ref.tets},
                         {"seconds", ref.seconds},
                         {"coarser_mesh_mm", check_mm},
                         {"coarser_mesh_difference_mm_per_stage", check_diff_mm}};
  std::vector<double> stage_mm;
  for (double d : setup.stage_depths_m) stage_mm.push_back(d * 1e3);
  report["stages_probe_travel_mm"] = stage_mm;
  report["protocol"] = {{"warmup_steps", warmup}, {"steps_per_stage", per_stage}, {"step_s", setup.step_s}};
  nlohmann::json radii = nlohmann::json::array();
  struct Best {
    double radius_mm, compliance;
    st::PbdRun run;
  };
  std::vector<Best> best;
  for (double r_mm : radii_mm) {
    nlohmann::json curve = nlohmann::json::array();
    Best b{r_mm, 0.0, {}};
    b.run.mean_over_stages_m = INFINITY;
    for (double c : compliances) {
      st::SoftTissueSpec spec;
      spec.model.particle_radius_m = r_mm * 1e-3;
      spec.params.cluster_compliance_s2 = c;
      const auto t0 = std::chrono::steady_clock::now();
      st::PbdRun run = st::run_pbd_protocol(setup, spec, ref);
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      fmt::print(
          "  radius {} mm, compliance {:.0e}: mean fiducial error {:.2f} mm over the stages ({:.1f} s, step "
          "p50 {:.1f} ms)\n",
          r_mm, c, run.mean_over_stages_m * 1e3, s, pcisim::realtime::percentile(run.step_ms, 0.5));
      nlohmann::json stages = nlohmann::json::array();
      for (const auto& e : run.stages)
        stages.push_back({{"travel_mm", e.depth_m * 1e3},
                          {"mean_mm", e.mean_m * 1e3},
                          {"std_mm", e.std_m * 1e3},
                          {"max_mm", e.max_m * 1e3},
                          {"reference_displacement_mm", e.mean_displacement_m * 1e3}});
      curve.push_back({{"compliance_s2", c},
                       {"mean_over_stages_mm", run.mean_over_stages_m * 1e3},
                       {"step_ms_p50", pcisim::realtime::percentile(run.step_ms, 0.5)},
                       {"step_ms_p99", pcisim::realtime::percentile(run.step_ms, 0.99)},
                       {"stages", stages}});
      if (run.mean_over_stages_m < b.run.mean_over_stages_m) b.compliance = c, b.run = run;
    }
    radii.push_back({{"radius_mm", r_mm}, {"optimal_compliance_s2", b.compliance}, {"search", curve}});
    best.push_back(b);
  }
  report["radii"] = radii;
  std::ofstream(out + ".json") << report.dump(1) << "\n";

  // the paper's tables: stages x radius, each radius at its optimal compliance
  std::string md = fmt::format(
      "# Soft-tissue calibration (generated by `pcisim-calibrate`; do not edit)\n\n"
      "Reference: static neo-Hookean FEM of the procedural kidney (seed {}), E = {} kPa, nu = {}, linear tets "
      "of {} mm {} ({} nodes, {} tets, {:.0f} s on this machine), the same probe and gravity as the PBD, the "
      "support sticking (a node that reaches it stays where it touched; PBD: sticking friction), the probe "
      "frictionless. Protocol: {} warm-up steps, the probe moved over {} steps of 1/60 s to each stage. "
      "Search: cluster compliance in {{{}}} s^2.\n\n",
      seed, young_kpa, poisson, fem_mm,
      mesher == "tetgen" ? "from TetGen (body-fitted to the organ's surface)" : "on the voxelised organ (Kuhn tets)",
      ref.nodes, ref.tets, ref.seconds, warmup, per_stage, fmt::join(compliances, ", "));
  for (const char* what : {"mean", "std", "max"}) {
    md += fmt::format(
        "**Fiducial {} error (mm)**\n\n| probe travel (mm) | reference's mean fiducial displacement (mm) | "
        "{} mm reference vs {} mm (mm) |",
        what, check_mm, fem_mm);
    for (const Best& b : best) md += fmt::format(" r {} mm, c {:.0e} |", b.radius_mm, b.compliance);
    md += "\n|---|---|---|";
    for (size_t i = 0; i < best.size(); ++i) md += "---|";
    md += "\n";
    for (size_t k = 0; k < best.front().run.stages.size(); ++k) {
      const auto& e0 = best.front().run.stages[k];
      md += fmt::format("| {:.0f} | {:.2f} | {} |", e0.depth_m * 1e3, e0.mean_displacement_m * 1e3,
                        k < check_diff_mm.size() ? fmt::format("{:.2f}", check_diff_mm[k]) : "-");
      for (const Best& b : best) {
        const auto& e = b.run.stages[k];
        const double v = what[0] == 'm' && what[1] == 'e' ? e.mean_m : what[0] == 's' ? e.std_m : e.max_m;
        md += fmt::format(" {:.2f} |", v * 1e3);
      }
      md += "\n";
    }
    md += "\n";
  }
  md += "**Mean error over the stages (mm) against compliance**\n\n| compliance (s^2) |";
  for (const Best& b : best) md += fmt::format(" r {} mm |", b.radius_mm);
  md += "\n|---|";
  for (size_t i = 0; i < best.size(); ++i) md += "---|";
  md += "\n";
  for (size_t ci = 0; ci < compliances.size(); ++ci) {
    md += fmt::format("| {:.0e} |", compliances[ci]);
    for (const auto& r : radii) md += fmt::format(" {:.2f} |", r["search"][ci]["mean_over_stages_mm"].get<double>());
    md += "\n";
  }
  md += "\n**PBD step time at the optimum (ms, this machine)**\n\n| radius (mm) | p50 | p99 |\n|---|---|---|\n";
  for (const Best& b : best)
    md += fmt::format("| {} | {:.1f} | {:.1f} |\n", b.radius_mm, pcisim::realtime::percentile(b.run.step_ms, 0.5),
                      pcisim::realtime::percentile(b.run.step_ms, 0.99));
  std::ofstream(out + ".md") << md;
  fmt::print("wrote {}.json and {}.md\n", out, out);
  return 0;
}
