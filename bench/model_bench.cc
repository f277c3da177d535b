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

// Schaap et al. score each vessel from its ostium: the points of both trees inside the true
// aortic lumen (the phantom's trees, and the model's, start on the aortic centerline) are cut off
anatomy::VesselTree outside_aorta(const anatomy::VesselTree& tree, const anatomy::VesselTree& truth) {
  const int a = truth.find("aorta");
  if (a < 0) return tree;
  const auto& aorta = truth.branches[a];
  auto inside = [&](const Vector3d& p) {
    for (size_t i = 0; i + 1 < aorta.points.size(); ++i) {
      const Vector3d x = aorta.points[i].position_m, ab = aorta.points[i + 1].position_m - x;
      const double t = std::clamp((p - x).dot(ab) / std::max(ab.squaredNorm(), 1e-18), 0.0, 1.0);
      const double r = aorta.points[i].radius_m + t * (aorta.points[i + 1].radius_m - aorta.points[i].radius_m);
      if ((x + t * ab - p).norm() < r) return true;
    }
    return false;
  };
  anatomy::VesselTree out = tree;
  for (auto& b : out.branches) {
    if (b.name == "aorta" || b.parent < 0 || tree.branches[b.parent].name != "aorta") continue;
    // a tree's first branch: drop its leading points inside the aorta; its children's junction
    // indices move with it
    size_t cut = 0;
    while (cut + 2 < b.points.size() && inside(b.points[cut].position_m)) ++cut;
    if (cut == 0) continue;
    const int self = static_cast<int>(&b - out.branches.data());
    b.points.erase(b.points.begin(), b.points.begin() + cut);
    for (auto& c : out.branches) {
      if (c.parent == self) c.parent_point = std::max(0, c.parent_point - static_cast<int>(cut));
    }
  }
  return out;
}

Row run_one(const Setting& s, uint32_t phantom) {
  Row r;
  r.s = s;
  r.phantom = phantom;
  anatomy::PhantomCtaSpec spec;
  spec.seed = phantom;
  spec.noise_sigma_hu = s.noise_hu;
  spec.spacing_mm = s.voxel_mm;
  spec.dims = s.dims;
  anatomy::PhantomCta cta = anatomy::make_phantom_cta(spec);
  reset_peak_memory();
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const modeling::CtaModel m = modeling::build_cta_model(cta.ct, {cta.aortic_seed_mm}, s.options);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.peak_mib = modeling::peak_memory_mib();
    for (const auto& st : m.stages) r.stage_s.push_back({st.name, st.seconds});
    r.c = modeling::score_centerlines(outside_aorta(cta.truth, cta.truth), outside_aorta(m.model.vessels, cta.truth));
    anatomy::LumenMeshSpec ls;
    ls.exclude = {"aorta"};
    anatomy::LumenMeshSpec ms = s.options.lumen;
    ms.exclude = {"aorta"};
    r.lumen =
        modeling::score_lumen(anatomy::loft_lumen(cta.truth, ls), anatomy::loft_lumen(m.model.vessels, ms), 0.2e-3);
    r.dice = modeling::dice_of_trees(cta.truth, m.model.vessels, 0.1e-3);
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
    "  --quick: one phantom, fewer settings\n";

int run(const std::vector<std::string>& args) {
  BenchOptions bo;
  if (const int rc = parse_bench_options(args, "model", kUsage, &bo); rc >= 0) return rc;
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
        "radius error mean <= 0.15 mm, whole pipeline <= 60 s and <= 4 GB.\n\n";
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
    for (const auto& [n, t] : r.stage_s) md << fmt::format(" {:.2f} |", t);
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
