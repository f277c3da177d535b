// pcisim-calibrate: the soft-tissue paper's calibration (issue #16 item 5, issue #31 item 1) on
// the procedural kidney. For each particle radius, an exhaustive search over the cluster
// compliance (shape matching: 1/omega^2 of each cluster's pull), the bulk modulus of the clusters'
// volume constraint and the contact surface, minimising the mean fiducial error over the stages
// (rest included) against a static neo-Hookean FEM of the same organ under the same probe,
// support and gravity (physics/soft_tissue/calibration.h). The optimum of each radius is then run
// on a held-out kidney it was not tuned on. The solver is the CPU scene's Gauss-Seidel, or with
// --solver jacobi the CPU twin of the GPU's step (a scene with soft_tissue device cuda). Writes a JSON report and a
// Markdown summary: per stage the reference's bead motion (the error of a model that does not deform), the model's mean
// / std / max error and the fraction of the motion it explains, on both kidneys.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "anatomy/organ/kidney_phantom.h"
#include "bench/kidney_tetgen_mesh.h"
#include "physics/soft_tissue/calibration.h"
#include "realtime/percentile.h"

namespace st = pcisim::physics::soft_tissue;

namespace {

struct Setting {
  double radius_mm = 0.0, compliance = 0.0, bulk_kpa = 0.0;
  st::ContactSurface contact = st::ContactSurface::kSpheres;
};

const char* contact_name(st::ContactSurface c) {
  return c == st::ContactSurface::kSkin ? "skin" : "spheres";
}

std::string describe(const Setting& s) {
  return fmt::format("r {} mm, c {:.0e}, K {} kPa, {}", s.radius_mm, s.compliance, s.bulk_kpa, contact_name(s.contact));
}

// the objective: the mean of the stages' mean errors, rest included
double objective(const st::PbdRun& run) {
  double sum = 0.0;
  for (const st::StageError& e : run.stages) sum += e.mean_m;
  return run.stages.empty() ? INFINITY : sum / static_cast<double>(run.stages.size());
}

nlohmann::json stages_json(const st::PbdRun& run) {
  nlohmann::json stages = nlohmann::json::array();
  for (const auto& e : run.stages)
    stages.push_back(
        {{"travel_mm", e.depth_m * 1e3},
         {"mean_mm", e.mean_m * 1e3},
         {"std_mm", e.std_m * 1e3},
         {"max_mm", e.max_m * 1e3},
         {"reference_displacement_mm", e.mean_displacement_m * 1e3},
         {"explained", e.mean_displacement_m > 0.0 ? 1.0 - e.mean_m / e.mean_displacement_m : 0.0},
         {"mean_error_vector_mm", {e.mean_error_m.x() * 1e3, e.mean_error_m.y() * 1e3, e.mean_error_m.z() * 1e3}},
         {"shape_error_mm", e.shape_error_m * 1e3},
         {"response_ratio", e.response_ratio},
         {"reference_from_unloaded_mm", e.reference_from_unloaded_m * 1e3},
         {"model_from_unloaded_mm", e.model_from_unloaded_m * 1e3}});
  return stages;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// written beside the file and renamed into place: a reader never sees half a reference
void write_text(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    out << text;
    if (!(out << std::flush)) throw std::runtime_error("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "pcisim-calibrate: calibrates the soft tissue against a neo-Hookean FEM of the procedural kidney (the paper's\n"
      "protocol: warm-up, the probe pressed in stages, mean fiducial error per stage). Searches the cluster\n"
      "compliance, the bulk modulus of the clusters' volume constraint and the contact surface per particle radius,\n"
      "then runs each radius's optimum on a held-out kidney. The FEM references are read from --references-dir\n"
      "(solved once by --solve-references: minutes each). Writes OUT.json and OUT.md."};
  std::vector<double> radii_mm{3.3, 4.0, 5.0};
  std::vector<double> compliances{5e-6, 1e-5, 2e-5, 3e-5, 5e-5, 1e-4};
  std::vector<double> bulk_kpa{0.0, 16.7, 100.0};
  std::vector<std::string> contacts{"spheres", "skin"};
  double young_kpa = 5.0, poisson = 0.45, fem_mm = 5.0, check_mm = 6.0;
  int warmup = 120, per_stage = 90;
  bool solve = false;
  std::string mesher = "tetgen";
  std::string out = "docs/benchmarks/soft-tissue-calibration";
  std::string references_dir = "docs/benchmarks";
  std::string solver = "gauss_seidel";
  double sor_w = 1.5;
  int substeps = st::TissueParams{}.substeps, iterations = st::TissueParams{}.iterations;
  app.add_option("--radii-mm", radii_mm, "particle radii to calibrate (the paper: 2.2-3.3 mm)")
      ->check(CLI::Range(1.5, 20.0));
  app.add_option("--compliances", compliances, "the cluster compliances searched (s^2; smaller is stiffer)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--bulk-kpa", bulk_kpa,
                 "the bulk moduli of the clusters' volume constraint searched (kPa; 0 = none, shape matching "
                 "alone; the reference's own is E / (3 (1 - 2 nu)) = 16.7 kPa)")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--contacts", contacts, "the contact surfaces searched: spheres (the paper's) and/or skin")
      ->check(CLI::IsMember({"spheres", "skin"}));
  app.add_option("--young-kpa", young_kpa, "the reference's Young's modulus")->check(CLI::Range(0.1, 1000.0));
  app.add_option("--poisson", poisson, "the reference's Poisson's ratio")->check(CLI::Range(0.0, 0.49));
  app.add_option("--fem-mm", fem_mm, "the reference's mesh spacing")->check(CLI::Range(1.0, 10.0));
  app.add_option("--check-mm", check_mm,
                 "with --solve-references: a coarser reference whose difference from the fine one estimates the "
                 "reference's own error (0: none)")
      ->check(CLI::Range(0.0, 20.0));
  app.add_option("--mesh", mesher,
                 "the reference's tets: tetgen (body-fitted, the organ's own surface) or voxel (Kuhn tets on "
                 "the voxelised organ, a stair-stepped surface)")
      ->check(CLI::IsMember({"tetgen", "voxel"}));
  app.add_option("--warmup-steps", warmup, "PBD steps before the first stage (the paper: 120)");
  app.add_option("--steps-per-stage", per_stage, "PBD steps the probe takes to each stage (the paper: 90)");
  app.add_option("--references-dir", references_dir,
                 "where the FEM references are kept (soft-tissue-reference-tuning.txt, "
                 "soft-tissue-reference-held-out.txt)");
  app.add_option("--solver", solver,
                 "the PBD solver calibrated: gauss_seidel (the CPU scene's) or jacobi (the CPU twin of the GPU's "
                 "step, soft_tissue device cuda: the same answer to summation order)")
      ->check(CLI::IsMember({"gauss_seidel", "jacobi"}));
  app.add_option("--substeps", substeps, "PBD substeps a step (both kidney scenes': 3)")
      ->check(CLI::Range(static_cast<int>(st::kTissueSubsteps.min), static_cast<int>(st::kTissueSubsteps.max)));
  app.add_option("--iterations", iterations,
                 "solver iterations a substep (scenes/kidney.json's: 9; kidney-gpu.json's: 27)")
      ->check(CLI::Range(static_cast<int>(st::kTissueIterations.min), static_cast<int>(st::kTissueIterations.max)));
  app.add_option("--sor-w", sor_w, "with --solver jacobi: its over-relaxation (the GPU scene's: 1.5)")
      ->check(CLI::Range(1.0, 2.0));
  app.add_flag("--solve-references", solve, "solve both FEM references and write them to --references-dir");
  app.add_option("--out", out, "report path without extension");
  CLI11_PARSE(app, argc, argv);
  try {
    // progress goes out line by line even into a pipe
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    const std::string mesh_words = fmt::format(
        "{} tets of {} mm", mesher == "tetgen" ? "TetGen (body-fitted)" : "voxel (Kuhn, stair-stepped)", fem_mm);

    struct Organ {
      const char* name;
      st::CalibrationOrgan which;
      pcisim::anatomy::KidneySpec spec;
      st::CalibrationSetup setup;
      st::FemReference ref;
      std::vector<double> check_diff_mm;
    };
    const bool jacobi = solver == "jacobi";
    if (!jacobi && app.count("--sor-w") > 0) {
      fmt::print(stderr, "pcisim-calibrate: --sor-w is Jacobi's over-relaxation: give it with --solver jacobi\n");
      return 2;
    }
    const std::string solver_words =
        jacobi ? fmt::format("{} substeps x {} Jacobi iterations, SOR w {}", substeps, iterations, sor_w)
               : fmt::format("{} substeps x {} Gauss-Seidel iterations", substeps, iterations);
    std::vector<Organ> organs;
    for (auto [name, which] :
         {std::pair{"tuning", st::CalibrationOrgan::kTuning}, std::pair{"held-out", st::CalibrationOrgan::kHeldOut}}) {
      Organ o{name, which, st::calibration_kidney(which), {}, {}, {}};
      o.setup =
          st::kidney_calibration_setup(pcisim::anatomy::kidney_organ(pcisim::anatomy::make_kidney_phantom(o.spec)));
      o.setup.young_pa = young_kpa * 1e3;
      o.setup.poisson = poisson;
      o.setup.fem_spacing_m = fem_mm * 1e-3;
      o.setup.warmup_steps = warmup;
      o.setup.steps_per_stage = per_stage;
      const std::string path =
          (std::filesystem::path(references_dir) / fmt::format("soft-tissue-reference-{}.txt", name)).string();
      auto mesh_at = [&](double spacing_m) {
        st::CalibrationSetup at = o.setup;
        at.fem_spacing_m = spacing_m;
        return mesher == "voxel" ? st::voxel_reference_mesh(at) : pcisim::bench::kidney_tetgen_mesh(o.spec, spacing_m);
      };
      if (solve) {
        fmt::print("{} kidney: solving the neo-Hookean FEM, E {} kPa, nu {}, {} ...\n", name, young_kpa, poisson,
                   mesh_words);
        o.ref = st::solve_fem_reference(o.setup, mesh_at(o.setup.fem_spacing_m));
        fmt::print("  {} nodes, {} tets, {:.1f} s; stages:", o.ref.nodes, o.ref.tets, o.ref.seconds);
        for (const auto& r : o.ref.solves)
          fmt::print(" [{} Newton, residual {:.1e} N{}]", r.newton_iterations, r.residual_n,
                     r.converged ? "" : ", NOT converged");
        fmt::print("\n");
        write_text(path, st::fem_reference_text(o.setup, o.ref, mesh_words));
        if (check_mm > 0) {
          // the reference's own discretisation error, estimated by a coarser mesh (not a bound)
          const st::FemReference c = st::solve_fem_reference(o.setup, mesh_at(check_mm * 1e-3));
          for (size_t k = 0; k < c.fiducials_m.size(); ++k)
            o.check_diff_mm.push_back((c.fiducials_m[k] - o.ref.fiducials_m[k]).colwise().norm().mean() * 1e3);
          fmt::print("  a {} mm reference differs from it by {} mm (mean over the beads, per stage)\n", check_mm,
                     fmt::join(o.check_diff_mm, ", "));
        }
      } else {
        std::string words;
        o.ref = st::parse_fem_reference(read_text(path), o.setup, path, &words);
        if (words != mesh_words) {
          fmt::print(stderr, "{}: solved on {}, not {}; run with --solve-references\n", path, words, mesh_words);
          return 2;
        }
        fmt::print("{} kidney: reference {} ({}, {} nodes, solved in {:.0f} s)\n", name, path, words, o.ref.nodes,
                   o.ref.seconds);
      }
      organs.push_back(std::move(o));
    }
    const Organ& tuning = organs[0];
    const Organ& held_out = organs[1];

    // the search, on the tuning kidney only
    struct Result {
      Setting setting;
      st::PbdRun run;
      double objective_m = INFINITY;
    };
    std::vector<Result> all;
    std::vector<Result> best(radii_mm.size()), best_paper(radii_mm.size());
    auto run_on = [&](const Organ& o, const Setting& s) {
      st::SoftTissueSpec spec;
      spec.model.particle_radius_m = s.radius_mm * 1e-3;
      spec.params.cluster_compliance_s2 = s.compliance;
      spec.params.bulk_modulus_pa = s.bulk_kpa * 1e3;
      spec.params.contact_surface = s.contact;
      spec.params.substeps = substeps;
      spec.params.iterations = iterations;
      if (jacobi) {
        spec.params.solver = pcisim::physics::pbd::SolverKind::kJacobi;
        spec.params.sor_w = sor_w;
      }
      return st::run_pbd_protocol(o.setup, spec, o.ref);
    };
    const size_t total = radii_mm.size() * compliances.size() * bulk_kpa.size() * contacts.size();
    for (size_t ri = 0; ri < radii_mm.size(); ++ri)
      for (const std::string& contact : contacts)
        for (double k : bulk_kpa)
          for (double c : compliances) {
            Result r;
            r.setting = {radii_mm[ri], c, k,
                         contact == "skin" ? st::ContactSurface::kSkin : st::ContactSurface::kSpheres};
            const auto t0 = std::chrono::steady_clock::now();
            r.run = run_on(tuning, r.setting);
            r.objective_m = objective(r.run);
            const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            fmt::print("  [{}/{}] {}: mean error {:.2f} mm over the stages ({:.1f} s, step p50 {:.1f} ms)\n",
                       all.size() + 1, total, describe(r.setting), r.objective_m * 1e3, sec,
                       pcisim::realtime::percentile(r.run.step_ms, 0.5));
            if (r.objective_m < best[ri].objective_m) best[ri] = r;
            // the paper's model: shape matching alone, particle spheres
            if (k == 0.0 && contact == "spheres" && r.objective_m < best_paper[ri].objective_m) best_paper[ri] = r;
            all.push_back(std::move(r));
          }

    // each optimum, and the paper's model's, on the held-out kidney (not re-tuned)
    std::vector<st::PbdRun> transfer, transfer_paper;
    for (size_t ri = 0; ri < radii_mm.size(); ++ri) {
      transfer.push_back(run_on(held_out, best[ri].setting));
      fmt::print("  held out, {}: mean error {:.2f} mm over the stages\n", describe(best[ri].setting),
                 objective(transfer.back()) * 1e3);
      transfer_paper.push_back(best_paper[ri].objective_m < INFINITY ? run_on(held_out, best_paper[ri].setting)
                                                                     : st::PbdRun{});
    }

    // the JSON report
    nlohmann::json report;
    auto organ_json = [&](const Organ& o) {
      return nlohmann::json{
          {"semi_axes_mm", {o.spec.semi_axes_mm.x(), o.spec.semi_axes_mm.y(), o.spec.semi_axes_mm.z()}},
          {"hilum_depth", o.spec.hilum_depth},
          {"seed", o.spec.seed},
          {"reference_nodes", o.ref.nodes},
          {"reference_tets", o.ref.tets},
          {"reference_seconds", o.ref.seconds},
          {"coarser_mesh_difference_mm_per_stage", o.check_diff_mm}};
    };
    report["reference"] = {{"model", "static neo-Hookean FEM, linear tets"},
                           {"mesh", mesh_words},
                           {"young_kpa", young_kpa},
                           {"poisson", poisson},
                           {"spacing_mm", fem_mm},
                           {"coarser_mesh_mm", solve ? check_mm : 0.0}};
    report["organs"] = {{"tuning", organ_json(tuning)}, {"held_out", organ_json(held_out)}};
    std::vector<double> stage_mm;
    for (double d : tuning.setup.stage_depths_m) stage_mm.push_back(d * 1e3);
    report["stages_probe_travel_mm"] = stage_mm;
    report["protocol"] = {{"warmup_steps", warmup}, {"steps_per_stage", per_stage}, {"step_s", tuning.setup.step_s}};
    report["solver"] = {
        {"kind", solver}, {"substeps", substeps}, {"iterations", iterations}, {"sor_w", jacobi ? sor_w : 1.0}};
    report["objective"] = "mean over the stages (rest included) of the mean fiducial error";
    nlohmann::json search = nlohmann::json::array();
    for (const Result& r : all)
      search.push_back({{"radius_mm", r.setting.radius_mm},
                        {"compliance_s2", r.setting.compliance},
                        {"bulk_kpa", r.setting.bulk_kpa},
                        {"contact", contact_name(r.setting.contact)},
                        {"objective_mm", r.objective_m * 1e3},
                        {"step_ms_p50", pcisim::realtime::percentile(r.run.step_ms, 0.5)},
                        {"step_ms_p99", pcisim::realtime::percentile(r.run.step_ms, 0.99)},
                        {"stages", stages_json(r.run)}});
    report["search"] = search;
    nlohmann::json optima = nlohmann::json::array();
    for (size_t ri = 0; ri < radii_mm.size(); ++ri) {
      const Setting& s = best[ri].setting;
      optima.push_back({{"radius_mm", s.radius_mm},
                        {"compliance_s2", s.compliance},
                        {"bulk_kpa", s.bulk_kpa},
                        {"contact", contact_name(s.contact)},
                        {"tuning", stages_json(best[ri].run)},
                        {"held_out", stages_json(transfer[ri])},
                        {"paper_model",
                         {{"compliance_s2", best_paper[ri].setting.compliance},
                          {"tuning", stages_json(best_paper[ri].run)},
                          {"held_out", stages_json(transfer_paper[ri])}}}});
    }
    report["optima"] = optima;
    std::ofstream(out + ".json") << report.dump(1) << "\n";

    // the summary
    std::string md = fmt::format(
        "# Soft-tissue calibration (generated by `pcisim-calibrate`; do not edit)\n\n"
        "Reference: static neo-Hookean FEM, E = {} kPa, nu = {}, linear tets: {} (tuning kidney {} nodes, "
        "held-out kidney {} nodes), the same probe and gravity as the PBD, the support sticking (a node that "
        "reaches it stays where it touched; PBD: sticking friction), the probe frictionless. Protocol: {} warm-up "
        "steps, the probe moved over {} steps of 1/60 s to each stage; the PBD solved with {}. Search on the "
        "tuning kidney (the phantom's "
        "defaults, seed {}): cluster compliance in {{{}}} s^2 x bulk modulus in {{{}}} kPa x contact surface in "
        "{{{}}}, objective the mean fiducial error over the stages, rest included. The held-out kidney ({} x {} x "
        "{} mm semi-axes, hilum {}, seed {}) was never run during the search. *Moved* is the reference's mean bead "
        "displacement from rest: the error of a model that does not deform. *Explained* = 1 - error / moved.\n\n",
        young_kpa, poisson, mesh_words, tuning.ref.nodes, held_out.ref.nodes, warmup, per_stage, solver_words,
        tuning.spec.seed, fmt::join(compliances, ", "), fmt::join(bulk_kpa, ", "), fmt::join(contacts, ", "),
        held_out.spec.semi_axes_mm.x(), held_out.spec.semi_axes_mm.y(), held_out.spec.semi_axes_mm.z(),
        held_out.spec.hilum_depth, held_out.spec.seed);
    auto stage_table = [&](const char* title, const std::vector<const st::PbdRun*>& runs,
                           const std::vector<std::string>& labels) {
      md += fmt::format("**{}** (mm; explained in %)\n\n| probe travel (mm) | moved (no deformation) |", title);
      for (const std::string& l : labels) md += fmt::format(" {} mean / std / max | explained |", l);
      md += "\n|---|---|";
      for (size_t i = 0; i < labels.size(); ++i) md += "---|---|";
      md += "\n";
      for (size_t k = 0; k < runs.front()->stages.size(); ++k) {
        const auto& e0 = runs.front()->stages[k];
        md += fmt::format("| {:.0f} | {:.2f} |", e0.depth_m * 1e3, e0.mean_displacement_m * 1e3);
        for (const st::PbdRun* r : runs) {
          const auto& e = r->stages[k];
          md += fmt::format(" {:.2f} / {:.2f} / {:.2f} | {} |", e.mean_m * 1e3, e.std_m * 1e3, e.max_m * 1e3,
                            e.mean_displacement_m >= 0.5e-3
                                ? fmt::format("{:.0f}", 100.0 * (1.0 - e.mean_m / e.mean_displacement_m))
                                : std::string("-"));
        }
        md += "\n";
      }
      md += "\n";
    };
    std::vector<std::string> labels;
    std::vector<const st::PbdRun*> tuned, moved, paper, paper_moved;
    for (size_t ri = 0; ri < radii_mm.size(); ++ri) {
      labels.push_back(describe(best[ri].setting));
      tuned.push_back(&best[ri].run);
      moved.push_back(&transfer[ri]);
    }
    stage_table("Tuning kidney, each radius at its optimum", tuned, labels);
    stage_table("Held-out kidney, the same settings (not re-tuned)", moved, labels);
    labels.clear();
    for (size_t ri = 0; ri < radii_mm.size(); ++ri)
      if (best_paper[ri].objective_m < INFINITY) {
        labels.push_back(describe(best_paper[ri].setting));
        paper.push_back(&best_paper[ri].run);
        paper_moved.push_back(&transfer_paper[ri]);
      }
    if (!paper.empty()) {
      stage_table("The paper's model (shape matching alone, particle spheres) at its optimum, tuning kidney", paper,
                  labels);
      stage_table("The paper's model, held-out kidney", paper_moved, labels);
    }
    // where the fields part (issue #31 item 1)
    md +=
        "**Where the model departs from the reference, each radius's optimum** (mm). *Shift*: the mean of the "
        "error vectors (x y z: what moving the whole model would take away); *shape*: the mean error once it is "
        "taken off (both means of distances: they do not add up to the error); *response*: the model's bead "
        "motion from its rest along the reference's, over the reference's (1: as far; below 1: stiffer; where the "
        "reference's beads moved 0.5 mm or more); *sag*: each side's mean bead displacement from the unloaded "
        "organ (at rest the reference's is the error of a model that does not sag under gravity).\n\n"
        "| kidney | setting | travel | error | shift x / y / z | shape | response | sag: reference / model |\n"
        "|---|---|---|---|---|---|---|---|\n";
    for (size_t ri = 0; ri < radii_mm.size(); ++ri)
      for (int side = 0; side < 2; ++side) {
        const st::PbdRun& r = side == 0 ? best[ri].run : transfer[ri];
        for (const st::StageError& e : r.stages)
          md += fmt::format(
              "| {} | {} | {:.0f} | {:.2f} | {:+.2f} / {:+.2f} / {:+.2f} | {:.2f} | {} | {:.2f} / {:.2f} |\n",
              side == 0 ? "tuning" : "held-out", describe(best[ri].setting), e.depth_m * 1e3, e.mean_m * 1e3,
              e.mean_error_m.x() * 1e3, e.mean_error_m.y() * 1e3, e.mean_error_m.z() * 1e3, e.shape_error_m * 1e3,
              e.mean_displacement_m >= 0.5e-3 ? fmt::format("{:.2f}", e.response_ratio) : std::string("-"),
              e.reference_from_unloaded_m * 1e3, e.model_from_unloaded_m * 1e3);
      }
    md += "\n";
    md += "**Objective (mm) over the search, tuning kidney**\n\n| radius (mm) | contact | bulk (kPa) |";
    for (double c : compliances) md += fmt::format(" c {:.0e} |", c);
    md += "\n|---|---|---|";
    for (size_t i = 0; i < compliances.size(); ++i) md += "---|";
    md += "\n";
    for (size_t i = 0; i < all.size(); i += compliances.size()) {
      const Setting& s = all[i].setting;
      md += fmt::format("| {} | {} | {} |", s.radius_mm, contact_name(s.contact), s.bulk_kpa);
      for (size_t j = 0; j < compliances.size() && i + j < all.size(); ++j)
        md += fmt::format(" {:.2f} |", all[i + j].objective_m * 1e3);
      md += "\n";
    }
    md += fmt::format(
        "\n**PBD step time at each optimum (ms, this machine, {}, one thread)**\n\n"
        "| setting | p50 | p99 |\n|---|---|---|\n",
        solver_words);
    for (const Result& b : best)
      md += fmt::format("| {} | {:.1f} | {:.1f} |\n", describe(b.setting),
                        pcisim::realtime::percentile(b.run.step_ms, 0.5),
                        pcisim::realtime::percentile(b.run.step_ms, 0.99));
    md += fmt::format("\n![error against stage]({}.png)\n", std::filesystem::path(out).filename().string());
    std::ofstream(out + ".md") << md;
    fmt::print("wrote {}.json and {}.md\n", out, out);
  } catch (const std::exception& e) {  // a reference that is not this setup's, a file that cannot be written
    fmt::print(stderr, "pcisim-calibrate: {}\n", e.what());
    return 2;
  }
  return 0;
}
