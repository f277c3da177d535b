// pcisim-bench model: what the CTA pipeline's accuracy costs (docs/modeling.md). Synthetic CTAs
// with exact truth (anatomy/phantom/phantom_cta) at clinical size are modelled from their aortic
// seed alone, and the model is scored against the truth as the Rotterdam coronary centerline
// evaluation does (Schaap et al. 2009: OV, OF, OT, AI; modeling/evaluation/centerline_scores.h),
// with the radius error, the lumen surface distance (mean, 95 % Hausdorff) and Dice. Sweeps noise
// x voxel size over several phantoms at the default knobs, then each knob (level-set iterations,
// cross-sections per mm, B-spline knot spacing, 2-D level-set iterations) at the target
// configuration (0.4 x 0.4 x 0.6 mm, sigma 25 HU). Writes model.md, model.json and (with
// /usr/bin/python3 + matplotlib) model.png into docs/benchmarks/ or --out DIR.
#ifdef PCISIM_HAVE_MODELING
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "anatomy/heart/heart_mesh.h"
#include "anatomy/heart/template_heart_surface.h"
#include "anatomy/phantom/phantom_cta.h"
#include "anatomy/vessel/lumen_mesh.h"
#include "bench/bench_options.h"
#include "bench/bench_registry.h"
#include "bench/bench_stats.h"
#include "bench/machine_info.h"
#include "modeling/cta/cta_pipeline.h"
#include "modeling/evaluation/centerline_scores.h"
#include "modeling/evaluation/lumen_scores.h"
#include "modeling/picture/model_overview.h"
#include "modeling/report/model_report.h"

namespace pcisim::bench {
namespace {

using Eigen::Vector3d;

struct Setting {
  std::string sweep;  // "noise x voxel" or the knob's name
  std::string knob;   // its value, for the table
  double noise_hu = 25;
  Vector3d voxel_mm{0.4, 0.4, 0.6};
  std::array<int64_t, 3> dims{512, 512, 250};
  modeling::CtaPipelineOptions options;
  std::vector<uint32_t> phantoms;  // empty: the sweep's phantoms
  bool family = false;             // the phantoms are family members (their seeds draw the scan)
};

struct Row {
  Setting s;
  uint32_t phantom = 0;
  bool failed = false;
  std::string error;
  modeling::CenterlineScores c;
  modeling::LumenScores lumen;
  double dice = 0;
  double seconds = 0, peak_mib = 0;
  std::vector<std::pair<std::string, double>> stage_s;
  // the template's epicardium against the painted heart (a sphere): as placed, and fitted (mm)
  std::array<double, 3> heart_placed{}, heart_fitted{};  // mean, p95, max
  bool heart_was_fitted = false;
  anatomy::PhantomCtaSpec spec;
  anatomy::PhantomCtaFacts facts;
  std::map<std::string, double> false_causes;  // family cases: false_by_cause
};

// distance to the phantom's painted heart over the epicardial vertices of the template mesh with
// these vertices (template frame) posed: mean, p95, max (mm)
std::array<double, 3> epicardium_error_mm(const anatomy::PhantomCta& cta, const anatomy::HeartPose& pose,
                                          const Eigen::Matrix3Xd& vertices_m) {
  std::vector<double> d;
  for (int i : anatomy::marked_surface_vertices(anatomy::template_heart_mesh(), anatomy::kEpicardium))
    d.push_back(anatomy::distance_to_painted_heart_mm(cta.facts, 1e3 * pose.to_case(vertices_m.col(i))));
  double mean = 0;
  for (double x : d) mean += x / double(d.size());
  return {mean, percentile(d, 0.95), percentile(d, 1.0)};
}

// resets the process's peak resident memory (Linux: "5" into clear_refs), so each run's is its own
void reset_peak_memory() {
  std::ofstream f("/proc/self/clear_refs");
  f << "5";
}

// the share of extracted centerline that matches nothing (mm): false positives x the sample step
double false_mm(const modeling::CenterlineScores& c) {
  return c.fp * modeling::CenterlineScoreOptions{}.sample_spacing_m * 1e3;
}
double missed_mm(const modeling::CenterlineScores& c) {
  return c.fn * modeling::CenterlineScoreOptions{}.sample_spacing_m * 1e3;
}

// the model against the truth, point by point (a diagnosis and a picture; the tables' false and
// missed lengths are the scorer's): a modelled centerline point farther from every true point
// than that point's radius is false, a true point with no modelled point within its radius is
// missed. Each false point is given to the drawn structure it lies in or beside (within 1 mm of
// its surface): a vein (beside or crossing an artery), the left atrial appendage, the stent, else
// "elsewhere" (chambers, myocardium, noise), with the length to the model's next point
struct Mismatch {
  modeling::OverviewMarks marks;
  std::map<std::string, double> false_by_cause_mm;
};

Mismatch mismatch(const anatomy::VesselTree& truth, const anatomy::VesselTree& model,
                  const anatomy::PhantomCtaFacts& f) {
  Mismatch out;
  auto near_polyline = [](const std::vector<Vector3d>& pts, const Vector3d& q, double r) {
    for (const auto& p : pts) {
      if ((p - q).norm() < r) return true;
    }
    return false;
  };
  auto within = [](const anatomy::VesselTree& tree, const Vector3d& q, double radius_m, bool use_own_radius) {
    for (const auto& t : tree.branches) {
      if (t.name == "aorta") continue;
      for (const auto& p : t.points) {
        if ((p.position_m - q).norm() <= (use_own_radius ? p.radius_m : radius_m)) return true;
      }
    }
    return false;
  };
  for (const auto& b : model.branches) {
    if (b.name == "aorta") continue;
    for (size_t i = 0; i + 1 < b.points.size(); ++i) {
      const Vector3d q = b.points[i].position_m;
      if (within(truth, q, 0, true)) continue;
      const double step_mm = (b.points[i + 1].position_m - q).norm() * 1e3;
      const Vector3d q_mm = q * 1e3;
      out.marks.false_mm.push_back(q_mm);
      std::string cause = "elsewhere";
      if (near_polyline(f.vein_points_mm, q_mm, f.vein_radius_mm + 1.0)) cause = "vein beside";
      for (const auto& v : f.crossing_veins) {
        if (near_polyline(v.points_mm, q_mm, v.radius_mm + 1.0)) cause = "crossing vein";
      }
      if (f.laa_gap_mm >= 0) {
        const Vector3d ab = f.laa_base_mm - f.laa_tip_mm;
        const double u = std::clamp((q_mm - f.laa_tip_mm).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
        const double r = f.laa_tip_radius_mm + u * (f.laa_base_radius_mm - f.laa_tip_radius_mm);
        if ((q_mm - f.laa_tip_mm - u * ab).norm() < r + 1.0) cause = "appendage";
      }
      if (!f.stent_branch.empty() && (q_mm - f.stent_center_mm).norm() < 0.5 * f.stent_length_mm + 2.0) cause = "stent";
      out.false_by_cause_mm[cause] += step_mm;
    }
  }
  for (const auto& t : truth.branches) {
    if (t.name == "aorta") continue;
    for (const auto& p : t.points) {
      if (!within(model, p.position_m, p.radius_m, false)) out.marks.missed_mm.push_back(p.position_m * 1e3);
    }
  }
  return out;
}

// the phantom a setting asks for: a family member draws its own scan
anatomy::PhantomCtaSpec phantom_spec(const Setting& s, uint32_t phantom) {
  if (s.family) return anatomy::family_phantom_cta_spec(phantom);
  anatomy::PhantomCtaSpec spec;
  spec.seed = phantom;
  spec.noise_sigma_hu = s.noise_hu;
  spec.spacing_mm = s.voxel_mm;
  spec.dims = s.dims;
  return spec;
}

Row run_one(const Setting& s, uint32_t phantom, const std::string& overview_png = "") {
  Row r;
  r.s = s;
  r.phantom = phantom;
  const anatomy::PhantomCta cta = anatomy::make_phantom_cta(phantom_spec(s, phantom));
  r.facts = cta.facts;
  r.spec = cta.spec;
  reset_peak_memory();
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const modeling::CtaModel m = modeling::build_cta_model(cta.ct, {cta.aortic_seed_mm}, s.options);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.peak_mib = modeling::peak_memory_mib();
    for (const auto& st : m.stages) r.stage_s.push_back({st.name, st.seconds});
    r.c = modeling::score_centerlines(modeling::outside_aorta(cta.truth, cta.truth),
                                      modeling::outside_aorta(m.model.vessels, cta.truth));
    anatomy::LumenMeshSpec ls;
    ls.exclude = {"aorta"};
    anatomy::LumenMeshSpec ms = s.options.lumen;
    ms.exclude = {"aorta"};
    r.lumen =
        modeling::score_lumen(anatomy::loft_lumen(cta.truth, ls), anatomy::loft_lumen(m.model.vessels, ms), 0.2e-3);
    r.dice = modeling::dice_of_trees(cta.truth, m.model.vessels, 0.1e-3);
    if (s.family) {
      const Mismatch mm = mismatch(cta.truth, m.model.vessels, cta.facts);
      r.false_causes = mm.false_by_cause_mm;
      if (!overview_png.empty()) {
        // the model over its CT, its false centerline and the truth it missed marked
        modeling::write_model_overview(cta.ct, m.model.vessels,
                                       fmt::format("FAMILY {} - MODEL: OV {:.3f} OT {:.3f} FALSE {:.0f} MM", phantom,
                                                   r.c.ov, r.c.ot, false_mm(r.c)),
                                       overview_png, &mm.marks);
      }
    }
    r.heart_placed = epicardium_error_mm(cta, m.model.heart, anatomy::template_heart_mesh().vertices_m);
    r.heart_was_fitted = m.model.heart_vertices_m.cols() > 0;
    if (r.heart_was_fitted) r.heart_fitted = epicardium_error_mm(cta, m.model.heart, m.model.heart_vertices_m);
  } catch (const std::exception& e) {
    r.failed = true;
    r.error = e.what();
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return r;
}

std::string voxel_text(const Vector3d& v) {
  return fmt::format("{:.1f}x{:.1f}x{:.1f}", v.x(), v.y(), v.z());
}

constexpr const char* kUsage =
    "pcisim-bench model [--quick] [--no-plot] [--out DIR]\n"
    "  sweeps noise x voxel size and the pipeline's knobs over synthetic CTAs with exact truth;\n"
    "  --quick: one phantom, fewer settings\n"
    "pcisim-bench model --family N [--split tuning|heldout|both] [--no-plot] [--out DIR]\n"
    "  models N members of each split of the varied phantom family (pcisim-model --make-phantom-cta --family;\n"
    "  tuning seeds 1..N, held-out seeds 1001..1000+N) and the classic phantoms 1-7, and reports each split's\n"
    "  median, 5th percentile and worst (model-family.md, .json, .png and the worst cases' overviews);\n"
    "  --seeds a,b,c: those family members alone (no classic phantoms), for a closer look;\n"
    "  --robust: the robust fill of pcisim-model --robust-fill (smoothed fill and tube growth)\n";

// a number for JSON: NaN (a model matching nothing has no AI) as null
std::string json_number(double x) {
  return std::isfinite(x) ? fmt::format("{}", x) : "null";
}

// "vein beside 120, elsewhere 30" (causes of a millimetre or more)
std::string causes_text(const std::map<std::string, double>& causes) {
  std::string out;
  for (const auto& [cause, mm] : causes) {
    if (mm < 1.0) continue;
    out += fmt::format("{}{} {:.0f}", out.empty() ? "" : ", ", cause, mm);
  }
  return out.empty() ? "-" : out;
}

// one group of cases (a split, or the classic phantoms) in the summary
struct Group {
  std::string name;
  std::vector<Row> rows;
};

// median, the bad tail's 5 % (low for a score, high for an error) and the worst
std::string spread(std::vector<double> v, bool higher_is_better, const char* format) {
  if (v.empty()) return "-";
  const double q = higher_is_better ? 0.05 : 0.95;
  const double worst = higher_is_better ? *std::min_element(v.begin(), v.end()) : *std::max_element(v.begin(), v.end());
  return fmt::format(fmt::runtime(std::string(format) + " / " + format + " / " + format), percentile(v, 0.5),
                     percentile(v, q), worst);
}

int run_family(int n, const std::string& split, const std::vector<uint32_t>& only, bool robust,
               const BenchOptions& bo) {
  std::vector<Group> groups;
  auto seeds = [&](uint32_t first) {
    std::vector<uint32_t> out;
    for (int i = 0; i < n; ++i) out.push_back(first + static_cast<uint32_t>(i));
    return out;
  };
  std::vector<std::pair<std::string, std::vector<uint32_t>>> plan;
  if (!only.empty()) {
    plan.push_back({"chosen", only});
  } else {
    if (split != "heldout") plan.push_back({"tuning", seeds(1)});
    if (split != "tuning") plan.push_back({"held-out", seeds(anatomy::kFamilyHeldOutFirstSeed)});
  }
  const std::string pictures = bo.out_dir + "/model-family", scratch = pictures + "/.all";
  std::filesystem::create_directories(scratch);
  for (const auto& [name, list] : plan) {
    Group g{name, {}};
    Setting s;
    s.sweep = name;
    s.knob = "family";
    s.family = true;
    if (robust) {
      s.options.segmentation.smoothing_mm = 0.5;
      s.options.segmentation.tubes.enabled = true;
    }
    for (uint32_t seed : list) {
      Row r = run_one(s, seed, fmt::format("{}/{}.png", scratch, seed));
      std::printf("%-8s %4u: %s  %.1f s\n", name.c_str(), seed,
                  r.failed ? ("FAILED: " + r.error).c_str()
                           : fmt::format("OV {:.3f} OT {:.3f} AI {:.3f} mm, radius {:.3f} mm, false {:.0f} mm, missed "
                                         "{:.0f} mm, {:.0f} MiB",
                                         r.c.ov, r.c.ot, r.c.ai_mm, r.c.radius_error_mean_mm, false_mm(r.c),
                                         missed_mm(r.c), r.peak_mib)
                                 .c_str(),
                  r.seconds);
      if (!r.failed && !r.false_causes.empty()) {
        std::printf("          false centerline by where it lies:");
        for (const auto& [cause, mm] : r.false_causes) std::printf(" %s %.0f mm;", cause.c_str(), mm);
        std::printf("\n");
      }
      std::fflush(stdout);
      g.rows.push_back(std::move(r));
    }
    groups.push_back(std::move(g));
  }
  // the classic phantoms at the target configuration, in the same run: the tuning split must be
  // no worse than these (issue #30)
  if (only.empty()) {
    Group g{"classic 1-7", {}};
    Setting s;
    s.sweep = "classic";
    s.knob = "0.4x0.4x0.6 mm, 25 HU";
    if (robust) {
      s.options.segmentation.smoothing_mm = 0.5;
      s.options.segmentation.tubes.enabled = true;
    }
    for (uint32_t p = 1; p <= 7; ++p) {
      Row r = run_one(s, p);
      std::printf("classic  %4u: OV %.3f OT %.3f AI %.3f mm, false %.0f mm  %.1f s\n", p, r.c.ov, r.c.ot, r.c.ai_mm,
                  false_mm(r.c), r.seconds);
      g.rows.push_back(std::move(r));
    }
    groups.push_back(std::move(g));
  }

  const std::string md_path = bo.out_dir + "/model-family.md", json_path = bo.out_dir + "/model-family.json";
  std::ofstream md(md_path), js(json_path);
  md << "# CTA modeling on a varied phantom family: tuning and held-out splits\n\n"
     << "Generated by `pcisim-bench model "
     << (only.empty() ? fmt::format("--family {}{}", n, split == "both" ? "" : " --split " + split)
                      : fmt::format("--seeds {}", fmt::join(only, ",")))
     << (robust ? " --robust" : "") << "` (bench/model_bench.cc); " << machine_info() << ".\n\n"
     << "Each case is a member of the phantom family (`pcisim-model --make-phantom-cta --family --seed N`; "
        "anatomy/phantom/phantom_cta.h): its seed draws the scan (voxels 0.3-0.8 mm in-plane and across slices, "
        "apart, a 512 matrix or wider, noise 15-45 HU, blur 0.3-0.6 mm, slices head- or feet-first) and the anatomy "
        "(heart size, shape and pose; myocardium 40-150 HU; lumen 300-550 HU falling off distally to 250; right heart "
        "unenhanced to enhanced; the aortic valve open or closed; right-ventricular free wall 2-5 mm; the left atrial "
        "appendage beside the LCx; a vein beside an artery and veins crossing arteries, 150-300 HU; calcium with "
        "blooming; a stent in half of them; small side branches down to 0.5 mm radius; the LAD-LCx angle 36-112 deg; "
        "a tortuous trunk in 40 %). Tuning seeds 1.., held-out seeds 1001.. (`kFamilyHeldOutFirstSeed`): the "
        "pipeline's development looks at the tuning split only. Modelled from the aortic seed alone, scored as "
        "docs/benchmarks/model.md describes (Schaap et al. 2009). False centerline: extracted centerline farther "
        "than the true radius from any true vessel (false positives x the 0.1 mm step); missed: true centerline "
        "without a match. Time and memory: the pipeline alone. The classic phantoms 1-7 (0.4 x 0.4 x 0.6 mm, "
        "25 HU) ran in the same run.\n\n"
     << "## Summary: median / 5 % tail / worst\n\n"
     << "The tail is the 5th percentile of a score (OV, OT) and the 95th of an error or a time.\n\n"
     << "| cases | n | failed | OV | OT | AI mm | radius error mm | false mm | missed mm | s | MiB worst |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Group& g : groups) {
    std::vector<double> ov, ot, ai, rad, fa, mi, sec;
    int failed = 0;
    double mib = 0;
    for (const Row& r : g.rows) {
      if (r.failed) {
        ++failed;
        ov.push_back(0);
        ot.push_back(0);
        continue;
      }
      ov.push_back(r.c.ov);
      ot.push_back(r.c.ot);
      // a model that matches nothing has no AI nor radius error (NaN): left out of their spreads
      if (std::isfinite(r.c.ai_mm)) ai.push_back(r.c.ai_mm);
      if (std::isfinite(r.c.radius_error_mean_mm)) rad.push_back(r.c.radius_error_mean_mm);
      fa.push_back(false_mm(r.c));
      mi.push_back(missed_mm(r.c));
      sec.push_back(r.seconds);
      mib = std::max(mib, r.peak_mib);
    }
    md << fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.0f} |\n", g.name, g.rows.size(), failed,
                      spread(ov, true, "{:.3f}"), spread(ot, true, "{:.3f}"), spread(ai, false, "{:.3f}"),
                      spread(rad, false, "{:.3f}"), spread(fa, false, "{:.0f}"), spread(mi, false, "{:.0f}"),
                      spread(sec, false, "{:.1f}"), mib);
  }
  // the targets, on the held-out split
  for (const Group& g : groups) {
    if (g.name != "held-out") continue;
    std::vector<double> ov, ai, fa, sec, mib;
    for (const Row& r : g.rows) {
      ov.push_back(r.failed ? 0.0 : r.c.ov);
      if (r.failed) continue;
      if (std::isfinite(r.c.ai_mm)) ai.push_back(r.c.ai_mm);
      fa.push_back(false_mm(r.c));
      sec.push_back(r.seconds);
      mib.push_back(r.peak_mib);
    }
    if (ai.empty()) break;
    auto verdict = [](bool met) { return met ? "met" : "**missed**"; };
    const double worst_false = *std::max_element(fa.begin(), fa.end());
    const double slowest = *std::max_element(sec.begin(), sec.end());
    const double biggest = *std::max_element(mib.begin(), mib.end());
    md << "\n## Targets (issue #30, held-out split)\n\n| target | measured | |\n|---|---|---|\n"
       << fmt::format("| median OV >= 0.95 | {:.3f} | {} |\n", percentile(ov, 0.5),
                      verdict(percentile(ov, 0.5) >= 0.95))
       << fmt::format("| 5th percentile OV >= 0.90 | {:.3f} | {} |\n", percentile(ov, 0.05),
                      verdict(percentile(ov, 0.05) >= 0.90))
       << fmt::format("| median AI <= 0.30 mm | {:.3f} | {} |\n", percentile(ai, 0.5),
                      verdict(percentile(ai, 0.5) <= 0.30))
       << fmt::format("| false centerline median <= 10 mm | {:.0f} | {} |\n", percentile(fa, 0.5),
                      verdict(percentile(fa, 0.5) <= 10))
       << fmt::format("| false centerline worst <= 40 mm | {:.0f} | {} |\n", worst_false, verdict(worst_false <= 40))
       << fmt::format("| every case <= 60 s | {:.1f} | {} |\n", slowest, verdict(slowest <= 60))
       << fmt::format("| every case <= 4 GB | {:.0f} MiB | {} |\n", biggest, verdict(biggest <= 4096));
  }
  // every case, with what its seed drew
  md << "\n## Every case\n\n"
     << "| split | seed | voxel mm | noise HU | myocardium HU | lumen HU | RV HU / wall mm | valve | LAA gap mm | "
        "stent | "
        "veins | tortuous | OV | OT | AI mm | radius mm | false mm | missed mm | s | MiB | false lies (mm) |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Group& g : groups) {
    if (g.name == "classic 1-7") continue;
    for (const Row& r : g.rows) {
      const auto& f = r.facts;
      const std::string scores =
          r.failed ? fmt::format("failed: {} ||||||||", r.error)
                   : fmt::format("{:.3f} | {:.3f} | {:.3f} | {:.3f} | {:.0f} | {:.0f} | {:.1f} | {:.0f} | {}", r.c.ov,
                                 r.c.ot, r.c.ai_mm, r.c.radius_error_mean_mm, false_mm(r.c), missed_mm(r.c), r.seconds,
                                 r.peak_mib, causes_text(r.false_causes));
      md << fmt::format(
          "| {} | {} | {:.2f} x {:.2f} | {:.0f} | {:.0f} | {:.0f}-{:.0f} | {:.0f} / {:.1f} | {} | {} | {} | "
          "{} | {} | {} |\n",
          g.name, r.phantom, r.spec.spacing_mm.x(), r.spec.spacing_mm.z(), r.spec.noise_sigma_hu, f.myocardium_hu,
          f.lumen_floor_hu, f.contrast_hu_proximal, f.rv_hu, f.rv_wall_mm, f.open_valve ? "open" : "closed",
          f.laa_gap_mm >= 0 ? fmt::format("{:.1f}", f.laa_gap_mm) : std::string("-"),
          f.stent_branch.empty() ? std::string("-") : f.stent_branch, 1 + f.crossing_veins.size(),
          f.tortuous_branch.empty() ? std::string("-") : f.tortuous_branch, scores);
    }
  }
  // the worst cases' overviews: the model over its CT
  md << "\n## The worst cases\n\nThe model's centerlines over the CT (maximum-intensity projections; "
        "`pcisim-model`'s overview), for each split the case of lowest OV and the case of most false centerline.\n\n";
  for (const Group& g : groups) {
    if (g.name == "classic 1-7" || g.rows.empty()) continue;
    auto worst_by = [&](auto key) {
      return std::max_element(g.rows.begin(), g.rows.end(),
                              [&](const Row& a, const Row& b) { return key(a) < key(b); });
    };
    std::vector<std::pair<std::string, const Row*>> picks = {
        {"lowest OV", &*worst_by([](const Row& r) { return r.failed ? 2.0 : 1.0 - r.c.ov; })},
        {"most false centerline", &*worst_by([](const Row& r) { return r.failed ? -1.0 : false_mm(r.c); })}};
    if (picks[0].second == picks[1].second) {
      picks[0].first = "lowest OV and most false centerline";
      picks.pop_back();
    }
    for (const auto& [why, r] : picks) {
      const std::string from = fmt::format("{}/{}.png", scratch, r->phantom);
      const std::string to = fmt::format("{}/{}-{}.png", pictures, g.name, r->phantom);
      std::error_code ec;
      std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing, ec);
      if (ec) continue;
      md << fmt::format("{} split, {} (seed {}: OV {:.3f}, false {:.0f} mm):\n\n![{} {}](model-family/{}-{}.png)\n\n",
                        g.name, why, r->phantom, r->c.ov, false_mm(r->c), g.name, r->phantom, g.name, r->phantom);
    }
  }
  std::filesystem::remove_all(scratch);
  js << "[\n";
  bool first = true;
  for (const Group& g : groups) {
    for (const Row& r : g.rows) {
      js << (first ? "" : ",\n")
         << fmt::format(
                "  {{\"group\": \"{}\", \"seed\": {}, \"failed\": {}, \"ov\": {}, \"ot\": {}, \"ai_mm\": {}, "
                "\"radius_mean_mm\": {}, \"false_mm\": {}, \"missed_mm\": {}, \"seconds\": {}, \"peak_mib\": {}}}",
                g.name, r.phantom, r.failed ? "true" : "false", r.c.ov, r.c.ot, json_number(r.c.ai_mm),
                json_number(r.c.radius_error_mean_mm), false_mm(r.c), missed_mm(r.c), r.seconds, r.peak_mib);
      first = false;
    }
  }
  js << "\n]\n";
  md.close();
  js.close();
  if (bo.plot && std::filesystem::exists("docs/benchmarks/model-family.py")) {
    if (run_plot_script("model",
                        "docs/benchmarks/model-family.py " + json_path + " " + bo.out_dir + "/model-family.png"))
      std::ofstream(md_path, std::ios::app) << "![OV and false centerline per case](model-family.png)\n";
  }
  std::printf("wrote %s and %s\n", md_path.c_str(), json_path.c_str());
  return 0;
}

int run(const std::vector<std::string>& args_in) {
  // --family N and --split S are this benchmark's own; the rest are every benchmark's
  std::vector<std::string> args;
  int family = 0;
  std::string split = "both";
  std::vector<uint32_t> only;  // --seeds: these family members alone (a look at a few cases)
  bool robust = false;
  for (size_t i = 0; i < args_in.size(); ++i) {
    if (args_in[i] == "--family" && i + 1 < args_in.size()) {
      family = std::atoi(args_in[++i].c_str());
      if (family < 1 || family > 500) {
        std::fprintf(stderr, "pcisim-bench model: --family takes 1..500 cases a split, got '%s'\n%s",
                     args_in[i].c_str(), kUsage);
        return 2;
      }
    } else if (args_in[i] == "--seeds" && i + 1 < args_in.size()) {
      std::string list = args_in[++i];
      for (size_t at = 0; at <= list.size();) {
        const size_t comma = std::min(list.find(',', at), list.size());
        const long v = std::atol(list.substr(at, comma - at).c_str());
        if (v < 1) {
          std::fprintf(stderr, "pcisim-bench model: --seeds takes family seeds a,b,c (each >= 1), got '%s'\n%s",
                       list.c_str(), kUsage);
          return 2;
        }
        only.push_back(static_cast<uint32_t>(v));
        at = comma + 1;
      }
      family = std::max(family, 1);
    } else if (args_in[i] == "--robust") {
      robust = true;
    } else if (args_in[i] == "--split" && i + 1 < args_in.size()) {
      split = args_in[++i];
      if (split != "tuning" && split != "heldout" && split != "both") {
        std::fprintf(stderr, "pcisim-bench model: --split takes tuning, heldout or both, got '%s'\n%s", split.c_str(),
                     kUsage);
        return 2;
      }
    } else {
      args.push_back(args_in[i]);
    }
  }
  BenchOptions bo;
  if (const int rc = parse_bench_options(args, "model", kUsage, &bo); rc >= 0) return rc;
  if (family > 0) return run_family(family, split, only, robust, bo);
  const std::vector<uint32_t> phantoms = bo.quick ? std::vector<uint32_t>{1} : std::vector<uint32_t>{1, 2, 3};
  std::vector<Setting> settings;
  // noise x voxel size at the default knobs; the field of view ~205 x 205 x 150 mm each time
  const std::vector<double> noises = bo.quick ? std::vector<double>{25} : std::vector<double>{10, 25, 40};
  const std::vector<Vector3d> voxels = bo.quick
                                           ? std::vector<Vector3d>{{0.4, 0.4, 0.6}}
                                           : std::vector<Vector3d>{{0.4, 0.4, 0.6}, {0.6, 0.6, 0.6}, {0.8, 0.8, 0.8}};
  for (const Vector3d& v : voxels) {
    for (double n : noises) {
      Setting s;
      s.sweep = "noise x voxel";
      s.knob = fmt::format("{} mm, {} HU", voxel_text(v), n);
      s.noise_hu = n;
      s.voxel_mm = v;
      for (int a = 0; a < 3; ++a) s.dims[a] = static_cast<int64_t>(std::lround(Vector3d(204.8, 204.8, 150)[a] / v[a]));
      settings.push_back(s);
    }
  }
  // each knob at the target configuration
  auto knob = [&](const std::string& name, const std::string& value, auto set) {
    Setting s;
    s.sweep = name;
    s.knob = value;
    set(s.options);
    settings.push_back(s);
  };
  for (int it : bo.quick ? std::vector<int>{0, 20} : std::vector<int>{0, 5, 20, 60}) {
    knob("level-set iterations", std::to_string(it), [&](auto& o) { o.segmentation.level_set.iterations = it; });
  }
  for (double sp : bo.quick ? std::vector<double>{0.5} : std::vector<double>{0.25, 0.5, 1.0, 2.0}) {
    knob("cross-section spacing mm", fmt::format("{}", sp), [&](auto& o) { o.spline.sample_spacing_mm = sp; });
  }
  for (double k : bo.quick ? std::vector<double>{3} : std::vector<double>{1.5, 3, 6, 12}) {
    knob("knot spacing mm", fmt::format("{}", k), [&](auto& o) { o.spline.knot_spacing_mm = k; });
  }
  for (int it : bo.quick ? std::vector<int>{150} : std::vector<int>{40, 80, 150, 400}) {
    knob("radius level-set iterations", std::to_string(it), [&](auto& o) { o.radius.iterations = it; });
  }

  // phantoms the pipeline's rules were not tuned on (they were tuned on 1, 2, 3), at the target
  // configuration: how well the rules generalise
  if (!bo.quick) {
    Setting s;
    s.sweep = "held-out phantoms";
    s.knob = "0.4x0.4x0.6 mm, 25 HU";
    s.phantoms = {4, 5, 6, 7, 8};
    settings.push_back(s);
  }

  std::vector<Row> rows;
  for (const Setting& s : settings) {
    for (uint32_t p : s.phantoms.empty() ? phantoms : s.phantoms) {
      Row r = run_one(s, p);
      std::printf("%-28s %-24s phantom %u: %s  %.1f s\n", s.sweep.c_str(), s.knob.c_str(), p,
                  r.failed ? ("FAILED: " + r.error).c_str()
                           : fmt::format("OV {:.3f} OF {:.3f} OT {:.3f} AI {:.3f} mm, radius {:.3f}/{:.3f} mm, surface "
                                         "{:.3f}/{:.3f} mm, Dice {:.3f}, heart {:.2f}/{:.2f} -> {:.2f}/{:.2f} mm",
                                         r.c.ov, r.c.of, r.c.ot, r.c.ai_mm, r.c.radius_error_mean_mm,
                                         r.c.radius_error_p95_mm, r.lumen.mean_mm, r.lumen.hausdorff95_mm, r.dice,
                                         r.heart_placed[0], r.heart_placed[1], r.heart_fitted[0], r.heart_fitted[1])
                                 .c_str(),
                  r.seconds);
      std::fflush(stdout);
      rows.push_back(std::move(r));
    }
  }

  // the report
  std::filesystem::create_directories(bo.out_dir);
  const std::string md_path = bo.out_dir + "/model.md", json_path = bo.out_dir + "/model.json";
  std::ofstream md(md_path), js(json_path);
  md << "# CTA modeling: accuracy against time\n\n"
     << "Generated by `pcisim-bench model" << (bo.quick ? " --quick" : "") << "` (bench/model_bench.cc); "
     << machine_info() << ".\n\n"
     << "Synthetic CTAs with exact truth (`pcisim-model --make-phantom-cta`, phantoms "
     << fmt::format("{}", fmt::join(phantoms, ", "))
     << "), modelled from the aortic seed alone with the pipeline of docs/modeling.md, scored against the truth "
        "as the Rotterdam coronary centerline evaluation defines it (Schaap et al., Med Image Anal 13(5), 2009; "
        "modeling/evaluation/centerline_scores.h states where its matching differs from theirs). OV, OF, OT: "
        "overlap, overlap until the first error, overlap over vessels at least 1.5 mm across; AI: mean distance of "
        "matched points, each vessel scored from its ostium (points inside the true aortic lumen cut off both trees); "
        "radius error over matched reference points (mean / p95); lumen surface distance between "
        "the lofted truth and the lofted model (mean / 95 % Hausdorff; aorta left out); Dice of the two lumens "
        "(0.1 mm voxels). Time: the model alone (reading and writing files excluded), one run each; memory: the "
        "process's peak during the run.\n\n"
     << "Targets (issue #13; 512 x 512 x 250 at 0.4-0.8 mm, sigma 25 HU): AI <= 0.3 mm, OV >= 95 %, OT >= 97 %, "
        "radius error mean <= 0.15 mm, whole pipeline <= 60 s and <= 4 GB.\n\n"
     << "These are the classic phantoms the pipeline's rules were shaped on. On a varied phantom family with a "
        "held-out split (issue #30): [model-family.md](model-family.md) (`pcisim-bench model --family 20`).\n\n";
  auto table = [&](const std::string& sweep) {
    md << "| " << (sweep == "noise x voxel" ? "voxel, noise" : sweep)
       << " | phantom | OV | OF | OT | AI mm | radius mean/p95 mm | surface mean/95%HD mm | Dice | s | MiB |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows) {
      if (r.s.sweep != sweep) continue;
      if (r.failed) {
        md << fmt::format("| {} | {} | failed: {} |||||||||\n", r.s.knob, r.phantom, r.error);
        continue;
      }
      md << fmt::format(
          "| {} | {} | {:.3f} | {:.3f} | {:.3f} | {:.3f} | {:.3f} / {:.3f} | {:.3f} / {:.3f} | {:.3f} | "
          "{:.1f} | {:.0f} |\n",
          r.s.knob, r.phantom, r.c.ov, r.c.of, r.c.ot, r.c.ai_mm, r.c.radius_error_mean_mm, r.c.radius_error_p95_mm,
          r.lumen.mean_mm, r.lumen.hausdorff95_mm, r.dice, r.seconds, r.peak_mib);
    }
    md << "\n";
  };
  md << "## Noise x voxel size (default knobs)\n\n";
  table("noise x voxel");
  for (const char* k :
       {"level-set iterations", "cross-section spacing mm", "knot spacing mm", "radius level-set iterations"}) {
    md << "## " << k << " (0.4 x 0.4 x 0.6 mm, 25 HU)\n\n";
    table(k);
  }
  if (!bo.quick) {
    md << "## Held-out phantoms (0.4 x 0.4 x 0.6 mm, 25 HU, default knobs)\n\n"
       << "The rules of docs/modeling.md were shaped on phantoms 1-3. These five were first scored after that; "
          "4 and 6 failed then and two rules came from them (gap bridging's contrast check: 4's costal cartilage; "
          "clipping's slenderness: 6's right atrium at the threshold); 8 fails as described in docs/modeling.md "
          "(its myocardium 1.3 noise sigmas under the lower threshold); 5 and 7 were only scored.\n\n";
    table("held-out phantoms");
  }
  // per-stage time at the target configuration (the first setting)
  md << "## Stage times at the target configuration (default knobs)\n\n| phantom |";
  for (const auto& [n, t] : rows.front().stage_s) md << " " << n << " s |";
  md << " total s |\n|---|";
  for (size_t i = 0; i <= rows.front().stage_s.size(); ++i) md << "---|";
  md << "\n";
  for (const Row& r : rows) {
    if (r.s.sweep != "noise x voxel" || r.s.knob != rows.front().s.knob || r.failed) continue;
    md << "| " << r.phantom << " |";
    // by the header's stage names; a second fill's stages ("segmentation (smoothed)") add to theirs
    for (const auto& [n, unused] : rows.front().stage_s) {
      double t = 0;
      for (const auto& [m, tm] : r.stage_s) t += (m == n || m == n + " (smoothed)") ? tm : 0.0;
      md << fmt::format(" {:.2f} |", t);
    }
    md << fmt::format(" {:.1f} |\n", r.seconds);
  }
  // the heart: the template's epicardium against the painted heart, placed and fitted
  md << "\n## Heart fit (stage g) at the target configuration\n\n"
     << "The phantoms paint the heart as a sphere of myocardium (50 mm x the drawn scale) in pericardial fat; the "
        "template's epicardium differs from it by its atrial bulges (up to 14 mm) and by what the placement from the "
        "vessels leaves. Distance from each epicardial vertex to the painted sphere, mm (mean / p95 / max), the "
        "template as placed under the modelled vessels and as fitted to the CT. Where the heart's base meets the "
        "mediastinum's soft tissue the CT shows no edge and the bulge stays (the max).\n\n"
     << "| phantom | placed mean / p95 / max | fitted mean / p95 / max | heart fit s |\n|---|---|---|---|\n";
  for (const Row& r : rows) {
    const bool target =
        (r.s.sweep == "noise x voxel" && r.s.knob == rows.front().s.knob) || r.s.sweep == "held-out phantoms";
    if (!target || r.failed || !r.heart_was_fitted) continue;
    double fit_s = 0;
    for (const auto& [n, t] : r.stage_s)
      if (n == "heart fit") fit_s = t;
    md << fmt::format("| {} | {:.2f} / {:.2f} / {:.1f} | {:.2f} / {:.2f} / {:.1f} | {:.2f} |\n", r.phantom,
                      r.heart_placed[0], r.heart_placed[1], r.heart_placed[2], r.heart_fitted[0], r.heart_fitted[1],
                      r.heart_fitted[2], fit_s);
  }
  // per-vessel scores of the first row, where the misses are
  md << "\n## Per vessel, phantom " << rows.front().phantom << " at the target configuration\n\n"
     << "| vessel (distal end) | length mm | OV | OF | AI mm | first miss at mm |\n|---|---|---|---|---|---|\n";
  for (const auto& v : rows.front().c.vessels) {
    md << fmt::format("| {} | {:.1f} | {:.3f} | {:.3f} | {:.3f} | {} |\n", v.name, v.length_mm, v.ov, v.of, v.ai_mm,
                      std::isnan(v.first_fn_mm) ? std::string("-") : fmt::format("{:.1f}", v.first_fn_mm));
  }
  js << "[\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    js << fmt::format(
        "  {{\"sweep\": \"{}\", \"knob\": \"{}\", \"phantom\": {}, \"failed\": {}, \"ov\": {}, \"of\": {}, \"ot\": {}, "
        "\"ai_mm\": {}, \"radius_mean_mm\": {}, \"radius_p95_mm\": {}, \"surface_mean_mm\": {}, \"surface_hd95_mm\": "
        "{}, "
        "\"dice\": {}, \"seconds\": {}, \"peak_mib\": {}, \"heart_placed_mean_mm\": {}, \"heart_fitted_mean_mm\": "
        "{}}}{}\n",
        r.s.sweep, r.s.knob, r.phantom, r.failed ? "true" : "false", r.c.ov, r.c.of, r.c.ot, r.c.ai_mm,
        r.c.radius_error_mean_mm, r.c.radius_error_p95_mm, r.lumen.mean_mm, r.lumen.hausdorff95_mm,
        std::isnan(r.dice) ? 0.0 : r.dice, r.seconds, r.peak_mib, r.heart_placed[0], r.heart_fitted[0],
        i + 1 < rows.size() ? "," : "");
  }
  js << "]\n";
  md.close();
  js.close();
  if (bo.plot && std::filesystem::exists("docs/benchmarks/model.py")) {
    run_plot_script("model", "docs/benchmarks/model.py " + json_path + " " + bo.out_dir + "/model.png");
    std::ofstream(md_path, std::ios::app) << "\n![accuracy against time](model.png)\n";
  }
  std::printf("wrote %s and %s\n", md_path.c_str(), json_path.c_str());
  return 0;
}

const bool registered = add("model", "CTA → model pipeline: Rotterdam scores, radius, surface against time", run);

}  // namespace
}  // namespace pcisim::bench
#endif
