// pcisim-bench blood: what the blood chain-mails' discretisation costs and buys. Knobs: the cell
// spacing along each centerline (0.25 mm is the reference) x the eq 12 link radius.
//  1. the field: BloodChainMail on the rest tree (phantom seed 1) stepped at 30 Hz through one
//     72 bpm cycle; at eight phases the eq 12 velocity at probe points (every 1 mm along the LM,
//     LAD, LCx and RCA, on the axis and at half the radius in four directions) against the
//     reference spacing at the same link radius: mean and max |dv|, mean |dv| relative to the
//     reference's mean speed; the probes no blood reaches; and the deviation from the analytic
//     pulsatile Poiseuille velocity at the probe (what the linking itself smooths away).
//  2. the scene: the full default beating scene over the built-in trainee's session with those
//     blood parameters: the blood effect's ms per step (p50, p99), and the wire tip's path against
//     the reference run's (same link radius): RMS and largest distance.
// Writes blood.md, blood.json and (with /usr/bin/python3 + matplotlib) blood.png into
// docs/benchmarks/ or --out DIR.
#include <fmt/format.h>

#include <Eigen/Geometry>
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
#include "physics/blood/blood_chain_mail.h"
#include "physics/guidewire/chain_mail_wire.h"
#include "physics/guidewire/sdf_lumen.h"
#include "anatomy/phantom/coronary_phantom.h"
#include "physics/world.h"

namespace pcisim::bench {
namespace {

using namespace pcisim::physics;
using Clock = std::chrono::steady_clock;
using Eigen::Vector3d;

constexpr double kDtS = 1.0 / 30.0;
constexpr double kReferenceSpacingMm = 0.25;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// a probe point inside a vessel and the analytic velocity there at flow fraction 1
struct Probe {
  Vector3d p_m;
  Vector3d poiseuille_m_per_s;  // 2 x mean x (1 - (r/R)^2) along the centerline, downstream
};

std::vector<Probe> make_probes(const anatomy::VesselTree& tree, double mean_m_per_s) {
  std::vector<Probe> probes;
  for (const auto& b : tree.branches) {
    if (b.name != "LM" && b.name != "LAD" && b.name != "LCx" && b.name != "RCA") continue;
    // every other point (the centerline is sampled every 0.5 mm), away from both ends
    for (size_t k = 4; k + 4 < b.points.size(); k += 2) {
      const Vector3d t = (b.points[k + 1].position_m - b.points[k - 1].position_m).normalized();
      Vector3d n = t.cross(Vector3d::UnitZ());
      if (n.norm() < 0.1) n = t.cross(Vector3d::UnitX());
      n.normalize();
      const Vector3d m = t.cross(n);
      const double r = b.points[k].radius_m;
      probes.push_back({b.points[k].position_m, 2.0 * mean_m_per_s * t});
      for (const Vector3d& d : {n, m, Vector3d(-n), Vector3d(-m)})
        probes.push_back({b.points[k].position_m + 0.5 * r * d, 2.0 * mean_m_per_s * (1.0 - 0.25) * t});
    }
  }
  return probes;
}

// the eq 12 velocity at every probe at eight phases of one cycle (probe-major within a phase)
struct FieldRun {
  std::vector<Vector3d> v;
  std::vector<double> flow_fraction;  // per phase
  int cells = 0;
  double step_ms = 0.0;  // median BloodChainMail::step over the cycle
};

FieldRun run_field(const BloodFlowParams& params, const anatomy::VesselTree& tree, const std::vector<Probe>& probes) {
  FieldRun run;
  BloodChainMail blood(params, tree);
  run.cells = blood.cell_count();
  const double cycle_s = 60.0 / 72.0;
  const int steps = static_cast<int>(std::lround(cycle_s / kDtS));
  std::vector<double> step_ms;
  int next_sample = 0;
  for (int s = 0; s < steps; ++s) {
    const double phase = (s + 1) * kDtS / cycle_s;
    const auto t0 = Clock::now();
    blood.step(kDtS, phase);
    step_ms.push_back(ms_since(t0));
    // eight samples spread over the cycle
    if (s == (next_sample * steps) / 8) {
      ++next_sample;
      run.flow_fraction.push_back(coronary_flow_fraction(phase, params.pulsatility));
      for (const Probe& p : probes) run.v.push_back(blood.linked_velocity(p.p_m));
    }
  }
  run.step_ms = percentile(step_ms, 0.5);
  return run;
}

// the full default beating scene with these blood parameters over the trainee's session
struct SceneRun {
  std::vector<Vector3d> tip_m;  // rest frame, every step
  std::vector<int> tip_branch;  // every step
  std::string final_branch;
  double blood_p50_ms = 0, blood_p99_ms = 0, step_p50_ms = 0;
};

SceneRun run_scene(const BloodFlowParams& blood, std::shared_ptr<const LumenQuery> lumen) {
  WorldSpec s = default_scene_spec();
  s.blood_flow = blood;
  World w(s, std::move(lumen));
  SceneRun r;
  std::vector<double> blood_ms, step_ms;
  WorldSnapshot snap;
  for (double t = 0.0; t <= kSessionS; t += kDtS) {
    const auto t0 = Clock::now();
    w.step(session_at(t));
    step_ms.push_back(ms_since(t0));
    for (const auto& c : w.effect_costs())
      if (c.name == "blood_flow") blood_ms.push_back(c.last_step_ms);
    r.tip_m.push_back(w.guidewire_state()->nodes_m().back());
    w.write_snapshot(snap);
    r.tip_branch.push_back(snap.tip_branch);
  }
  const int last = r.tip_branch.back();
  r.final_branch = last >= 0 ? w.vessel_tree().branches[last].name : "-";
  r.blood_p50_ms = percentile(blood_ms, 0.5);
  r.blood_p99_ms = percentile(blood_ms, 0.99);
  r.step_p50_ms = percentile(step_ms, 0.5);
  return r;
}

struct Row {
  double spacing_mm = 0, link_mm = 0;
  int cells = 0;
  double cell_step_ms = 0;
  double mean_dv_mm_s = 0, max_dv_mm_s = 0, rel_err = 0, unreached = 0, poiseuille_rel = 0;
  double blood_p50_ms = 0, blood_p99_ms = 0, step_p50_ms = 0, tip_rms_mm = 0, tip_max_mm = 0;
  double same_branch = 0;      // fraction of steps with the tip in the reference run's branch
  double tip_max_same_mm = 0;  // largest distance over those steps
  std::string final_branch;
};

constexpr const char* kUsage =
    "usage: pcisim-bench blood [--quick] [--out DIR] [--no-plot]\n"
    "  blood chain-mail spacing (0.25 mm reference, 0.5, 1, 2, 4 mm) x eq 12 link radius (0.75, 1.5, 3 mm):\n"
    "  the velocity field at probe points against the reference and the analytic Poiseuille flow, the\n"
    "  blood effect's cost and the wire tip's path in the full default scene. --quick: link radius 1.5 mm\n"
    "  only. Writes blood.md, blood.json, blood.png.\n";

int run_bench(const std::vector<std::string>& args) {
  BenchOptions o;
  if (const int rc = parse_bench_options(args, "blood", kUsage, &o); rc >= 0) return rc;
  std::filesystem::create_directories(o.out_dir);
  const std::string machine = machine_info();
  const std::vector<double> spacings_mm = {kReferenceSpacingMm, 0.5, 1.0, 2.0, 4.0};
  const std::vector<double> links_mm = o.quick ? std::vector<double>{1.5} : std::vector<double>{0.75, 1.5, 3.0};

  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({1});
  const BloodFlowParams defaults;
  const std::vector<Probe> probes = make_probes(tree, defaults.mean_velocity_m_per_s);
  auto sdf = std::make_shared<const SdfLumen>(tree, VesselContactParams{}.sdf_spacing_m);
  std::printf("blood: %zu probes, %zu x %zu settings\n", probes.size(), spacings_mm.size(), links_mm.size());

  std::vector<Row> rows;
  for (double link : links_mm) {
    FieldRun ref_field;
    SceneRun ref_scene;
    for (double spacing : spacings_mm) {
      BloodFlowParams p = defaults;
      p.cell_spacing_m = spacing * 1e-3;
      p.link_radius_m = link * 1e-3;
      const FieldRun field = run_field(p, tree, probes);
      const SceneRun scene = run_scene(p, sdf);
      if (spacing == kReferenceSpacingMm) {
        ref_field = field;
        ref_scene = scene;
      }
      Row r;
      r.spacing_mm = spacing;
      r.link_mm = link;
      r.cells = field.cells;
      r.cell_step_ms = field.step_ms;
      // field against the reference and against the analytic flow
      double sum_dv = 0, sum_ref = 0, sum_dp = 0, sum_p = 0;
      int unreached = 0;
      const size_t np = probes.size();
      for (size_t k = 0; k < field.v.size(); ++k) {
        const Vector3d poiseuille = probes[k % np].poiseuille_m_per_s * field.flow_fraction[k / np];
        const double dv = (field.v[k] - ref_field.v[k]).norm();
        sum_dv += dv;
        r.max_dv_mm_s = std::max(r.max_dv_mm_s, dv * 1e3);
        sum_ref += ref_field.v[k].norm();
        sum_dp += (field.v[k] - poiseuille).norm();
        sum_p += poiseuille.norm();
        unreached += field.v[k].squaredNorm() == 0.0;
      }
      const double n = static_cast<double>(field.v.size());
      r.mean_dv_mm_s = 1e3 * sum_dv / n;
      r.rel_err = sum_ref > 0 ? sum_dv / sum_ref : 0.0;
      r.unreached = unreached / n;
      r.poiseuille_rel = sum_p > 0 ? sum_dp / sum_p : 0.0;
      // the scene
      r.blood_p50_ms = scene.blood_p50_ms;
      r.blood_p99_ms = scene.blood_p99_ms;
      r.step_p50_ms = scene.step_p50_ms;
      double sq = 0;
      int same = 0;
      for (size_t k = 0; k < scene.tip_m.size(); ++k) {
        const double d = (scene.tip_m[k] - ref_scene.tip_m[k]).norm() * 1e3;
        sq += d * d;
        r.tip_max_mm = std::max(r.tip_max_mm, d);
        if (scene.tip_branch[k] == ref_scene.tip_branch[k]) {
          ++same;
          r.tip_max_same_mm = std::max(r.tip_max_same_mm, d);
        }
      }
      r.tip_rms_mm = std::sqrt(sq / static_cast<double>(scene.tip_m.size()));
      r.same_branch = same / static_cast<double>(scene.tip_m.size());
      r.final_branch = scene.final_branch;
      rows.push_back(r);
      std::printf(
          "blood: spacing %.2f mm link %.2f mm: %d cells, field err %.1f %% (max %.1f mm/s), unreached %.1f %%, "
          "vs Poiseuille %.1f %%; blood %.3f/%.3f ms p50/p99; tip RMS %.2f max %.2f mm, same branch %.0f %%, ends in "
          "%s\n",
          spacing, link, r.cells, 100 * r.rel_err, r.max_dv_mm_s, 100 * r.unreached, 100 * r.poiseuille_rel,
          r.blood_p50_ms, r.blood_p99_ms, r.tip_rms_mm, r.tip_max_mm, 100 * r.same_branch, r.final_branch.c_str());
    }
  }

  {
    std::ofstream f(o.out_dir + "/blood.json");
    f << "{\n"
      << fmt::format("  \"machine\": \"{}\",\n  \"quick\": {},\n  \"probes\": {},\n  \"rows\": [\n", machine, o.quick,
                     probes.size());
    for (size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      f << fmt::format(
          "    {{\"spacing_mm\": {}, \"link_mm\": {}, \"cells\": {}, \"cell_step_ms\": {:.4f}, \"mean_dv_mm_s\": "
          "{:.3f}, "
          "\"max_dv_mm_s\": {:.3f}, \"rel_err\": {:.5f}, \"unreached\": {:.5f}, \"poiseuille_rel\": {:.5f}, "
          "\"blood_p50_ms\": {:.4f}, \"blood_p99_ms\": {:.4f}, \"step_p50_ms\": {:.3f}, \"tip_rms_mm\": {:.4f}, "
          "\"tip_max_mm\": {:.4f}, \"same_branch\": {:.4f}, \"final_branch\": \"{}\"}}{}\n",
          r.spacing_mm, r.link_mm, r.cells, r.cell_step_ms, r.mean_dv_mm_s, r.max_dv_mm_s, r.rel_err, r.unreached,
          r.poiseuille_rel, r.blood_p50_ms, r.blood_p99_ms, r.step_p50_ms, r.tip_rms_mm, r.tip_max_mm, r.same_branch,
          r.final_branch, i + 1 < rows.size() ? "," : "");
    }
    f << "  ]\n}\n";
  }
  if (o.plot) o.plot = run_plot_script("blood", "docs/benchmarks/blood.py " + o.out_dir);
  {
    std::ofstream f(o.out_dir + "/blood.md");
    f << "# Blood chain-mails: spacing and link radius against a reference\n\n";
    f << fmt::format("Generated by `pcisim-bench blood{}` on {}; single-threaded, 30 Hz steps.\n\n",
                     o.quick ? " --quick" : "", machine);
    f << fmt::format(
        "**Field.** `BloodChainMail` on the rest tree (phantom seed 1; cells on the axis and a ring at 0.6 R every "
        "`cell_spacing`), stepped through one 72 bpm cycle (pulsatility {}); at eight phases the eq 12 velocity at "
        "{} probes (every 1 mm along the LM, LAD, LCx and RCA, on the axis and at half the radius in four directions) "
        "is compared with the {} mm run at the same link radius: mean |dv|, largest |dv|, and mean |dv| over the "
        "reference's mean speed. *Unreached*: probes with no blood chain-mail within the link radius (velocity 0). "
        "*vs Poiseuille*: mean |v - v_analytic| over the mean analytic speed, v_analytic = 2 u_mean q(phase) "
        "(1 - (r/R)^2) along the centerline: what the inverse-distance blend of eq 12 smooths away, at any "
        "spacing.\n\n",
        defaults.pulsatility, probes.size(), kReferenceSpacingMm);
    f << "**Scene.** The full default beating scene (heart, moving tree, 200-segment wire, contact, friction) over "
         "the built-in trainee's session (19.5 s at 30 Hz) with these blood parameters: the `blood_flow` effect's "
         "ms per step and the whole step's median; the wire tip's path (rest frame, every step) against the "
         "reference spacing's run at the same link radius.\n\n";
    f << "| spacing mm | link mm | cells | field err % | max dv mm/s | unreached % | vs Poiseuille % | cells step ms | "
         "blood p50 ms | blood p99 ms | step p50 ms | tip RMS mm | tip max mm | tip in ref's branch % | tip ends in |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows)
      f << fmt::format(
          "| {}{} | {} | {} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.3f} | {:.3f} | {:.3f} | {:.2f} | {:.2f} | {:.2f} "
          "| {:.0f} | {} |\n",
          r.spacing_mm, r.spacing_mm == kReferenceSpacingMm ? " (ref)" : "", r.link_mm, r.cells, 100 * r.rel_err,
          r.max_dv_mm_s, 100 * r.unreached, 100 * r.poiseuille_rel, r.cell_step_ms, r.blood_p50_ms, r.blood_p99_ms,
          r.step_p50_ms, r.tip_rms_mm, r.tip_max_mm, 100 * r.same_branch, r.final_branch);
    if (o.plot) f << "\n![field error and tip deviation against blood ms per step](blood.png)\n";
    // findings, computed from the rows above
    f << "\n## Findings (computed from the table)\n\n";
    for (double link : links_mm) {
      const Row* ref = nullptr;
      const Row* coarsest = nullptr;  // the coarsest spacing within 5 % of the reference field
      const Row* first_gap = nullptr;
      for (const Row& r : rows) {
        if (r.link_mm != link) continue;
        if (r.spacing_mm == kReferenceSpacingMm) ref = &r;
        if (r.rel_err <= 0.05 && r.unreached == 0.0 && (!coarsest || r.spacing_mm > coarsest->spacing_mm))
          coarsest = &r;
        if (r.unreached > 0.0 && (!first_gap || r.spacing_mm < first_gap->spacing_mm)) first_gap = &r;
      }
      if (!ref || !coarsest) continue;
      f << fmt::format(
          "- Link radius {} mm: the coarsest spacing within 5 % of the reference field is **{} mm** "
          "({:.1f} %, blood p50 {:.3f} ms against the reference's {:.3f} ms); its tip path stays within "
          "{:.2f} mm RMS of the reference's, in the reference's branch {:.0f} % of the steps.",
          link, coarsest->spacing_mm, 100 * coarsest->rel_err, coarsest->blood_p50_ms, ref->blood_p50_ms,
          coarsest->tip_rms_mm, 100 * coarsest->same_branch);
      if (first_gap)
        f << fmt::format(
            " From {} mm spacing some probes reach no blood ({:.1f} %): the cells are farther apart "
            "than the link radius reaches.",
            first_gap->spacing_mm, 100 * first_gap->unreached);
      f << "\n";
    }
    double smallest_max_dv = 1e300, largest_tip_max = 0.0, largest_tip_max_same = 0.0;
    for (const Row& r : rows)
      if (r.spacing_mm != kReferenceSpacingMm) {
        smallest_max_dv = std::min(smallest_max_dv, r.max_dv_mm_s);
        largest_tip_max = std::max(largest_tip_max, r.tip_max_mm);
        largest_tip_max_same = std::max(largest_tip_max_same, r.tip_max_same_mm);
      }
    f << fmt::format(
        "- The largest |dv| is at least {:.0f} mm/s in every non-reference row (peak flow on the axis is {:.0f} mm/s): "
        "a probe links to one vessel's blood, the vessel whose chain-mail is nearest, and near a fork a small "
        "shift of the cells can flip that choice. Read the mean error; the maximum is a few probes.\n",
        smallest_max_dv,
        1e3 * 2.0 * defaults.mean_velocity_m_per_s *
            coronary_flow_fraction(0.5 * (1.0 + kSystoleFraction), defaults.pulsatility));
    f << fmt::format(
        "- The tip's largest distance from the reference path is up to {:.1f} mm ({:.1f} mm over the steps where both "
        "tips are in the same branch): single steps of the wire's path differ far more than the session does; "
        "compare the RMS.\n",
        largest_tip_max, largest_tip_max_same);
  }
  std::printf("blood: wrote %s/blood.md, .json%s\n", o.out_dir.c_str(), o.plot ? ", .png" : "");
  return 0;
}

const bool registered =
    add("blood", "blood chain-mail spacing x link radius: field error, cost, wire tip path", run_bench);

}  // namespace
}  // namespace pcisim::bench
