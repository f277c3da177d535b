// pcisim-bench xray: what DRR accuracy costs. The seeded thorax phantom (512 x 512 x 256 at 0.7 mm)
// seen by a C-arm at LAO 30 / CRA 20 on 512^2 and 1024^2 detectors (same field of view): the exact
// Siddon projector is the reference and is timed too; the trilinear marcher on the CPU (and on the
// GPU when built with CUDA and one is present) is timed and compared with it for steps of 2, 1,
// 0.5 and 0.25 voxel. Writes xray.md, xray.json and (with python3-matplotlib) xray.png into
// docs/benchmarks/ or --out DIR.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench_registry.h"
#include "bench/bench_stats.h"
#include "bench/machine_info.h"
#include "bench/xray_plastimatch.h"
#include "anatomy/phantom/coronary_phantom.h"
#include "physics/world.h"
#include "xray/fluoro/beating_background.h"
#include "xray/fluoro/case_background.h"
#include "xray/fluoro/fluoroscopy.h"
#include "xray/frame/png_writer.h"
#include "xray/geometry/c_arm.h"
#include "anatomy/phantom/thorax_phantom.h"
#include "xray/projectors/attenuation_volume.h"
#include "xray/projectors/siddon_projector.h"
#include "xray/projectors/ray_packet.h"
#include "xray/projectors/trilinear_projector.h"
#ifdef PCISIM_HAVE_OSMESA
#include "xray/projectors/gl/gl_projector.h"
#endif
#ifdef PCISIM_HAVE_CUDA
#include "xray/projectors/cuda_projector.h"
#endif

namespace pcisim::bench {
namespace {

using namespace pcisim::xray;

struct Options {
  bool quick = false;
  bool fluoro_only = false;  // only the fluoroscopy section, printed (no files but its PNGs)
  std::string out_dir = "docs/benchmarks";
  int threads = 0;
  std::string plastimatch = "auto";  // the program, "auto" (the first on PATH) or "none"
  int plastimatch_images = 5;
  bool plastimatch_only = false;  // only the comparison with plastimatch, printed
};

struct Row {
  std::string projector;  // exact, cpu, cuda
  int detector = 0;
  double step = 0;  // 0 for exact
  double median_ms = 0, p99_ms = 0;
  double cpu_ms = 0;  // process CPU time per frame (all threads); wall ~ cpu / threads when no one else runs
  int frames = 0;
  double rmse_rel = 0, max_rel = 0;  // vs exact, relative to the largest exact line integral
};

double process_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

// wall ms of each frame; *cpu_ms: mean process CPU ms per frame
template <class Fn>
std::vector<double> time_frames(int warmup, int frames, double* cpu_ms, Fn&& fn) {
  for (int i = 0; i < warmup; ++i) fn();
  std::vector<double> ms;
  const double c0 = process_cpu_ms();
  for (int i = 0; i < frames; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  *cpu_ms = (process_cpu_ms() - c0) / frames;
  return ms;
}

void errors(const Image& got, const Image& ref, Row* row) {
  double peak = 0, sq = 0, worst = 0;
  for (float v : ref.pixels) peak = std::max(peak, double(v));
  for (size_t n = 0; n < ref.pixels.size(); ++n) {
    const double e = double(got.pixels[n]) - ref.pixels[n];
    sq += e * e;
    worst = std::max(worst, std::abs(e));
  }
  row->rmse_rel = std::sqrt(sq / ref.pixels.size()) / peak;
  row->max_rel = worst / peak;
}

// ---- fluoroscopy: cached background + analytic overlays vs full re-projection ----

struct FluoroResult {
  int detector = 0;
  int frames = 0;
  double build_ms = 0;                                             // renderer construction (phantom, attenuation)
  double background_ms = 0;                                        // one background projection (on a pose change)
  double frame_median_ms = 0, frame_p99_ms = 0, frame_cpu_ms = 0;  // per frame, pose unchanged
  double chain_median_ms = 0;                  // of which the image chain (noise, blur, log, window)
  double full_median_ms = 0, full_p99_ms = 0;  // full re-projection per frame (voxelise + mu + project + chain)
  double full_voxelise_ms = 0, full_mu_ms = 0, full_project_ms = 0;
  int full_frames = 0;
  double rmse_rel = 0, max_rel = 0;                  // line integrals, whole image, relative to max
  double overlay_rmse_rel = 0, overlay_max_rel = 0;  // the added iodine + wire only, relative to its max
  std::vector<std::string> pngs;
};

// adds add_hu x (the fraction of each voxel inside the rounded cone a-b) into frac as a maximum
// (joints between segments are not counted twice); sub^3 samples per partly covered voxel
void voxelise_cone(const anatomy::Volume& v, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double ra, double rb,
                   float value, int sub, std::vector<float>* frac) {
  const Eigen::Vector3d o = v.origin_mm, s = v.spacing_mm, ab = b - a;
  const double len2 = std::max(ab.squaredNorm(), 1e-12), rmax = std::max(ra, rb), rmin = std::min(ra, rb);
  const double half_diag = 0.5 * s.norm();
  int64_t lo[3], hi[3];
  for (int ax = 0; ax < 3; ++ax) {
    lo[ax] = std::max<int64_t>(0, static_cast<int64_t>(std::floor((std::min(a[ax], b[ax]) - rmax - o[ax]) / s[ax])));
    hi[ax] = std::min<int64_t>(v.dims[ax] - 1,
                               static_cast<int64_t>(std::ceil((std::max(a[ax], b[ax]) + rmax - o[ax]) / s[ax])));
    if (hi[ax] < lo[ax]) return;
  }
  auto inside = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d ap = p - a;
    const double u = std::clamp(ap.dot(ab) / len2, 0.0, 1.0);
    const double r = ra + (rb - ra) * u;
    return (ap - u * ab).squaredNorm() <= r * r;
  };
  for (int64_t k = lo[2]; k <= hi[2]; ++k) {
    for (int64_t j = lo[1]; j <= hi[1]; ++j) {
      for (int64_t i = lo[0]; i <= hi[0]; ++i) {
        const Eigen::Vector3d c = o + s.cwiseProduct(Eigen::Vector3d(i, j, k));
        const Eigen::Vector3d ac = c - a;
        const double u = std::clamp(ac.dot(ab) / len2, 0.0, 1.0);
        const double dist = (ac - u * ab).norm();
        double f;
        if (dist > rmax + half_diag) continue;
        if (dist + half_diag < rmin) {
          f = 1.0;
        } else {
          int in = 0;
          for (int z = 0; z < sub; ++z) {
            for (int y = 0; y < sub; ++y) {
              for (int x = 0; x < sub; ++x) {
                const Eigen::Vector3d q = c + s.cwiseProduct(Eigen::Vector3d(
                                                  (x + 0.5) / sub - 0.5, (y + 0.5) / sub - 0.5, (z + 0.5) / sub - 0.5));
                in += inside(q);
              }
            }
          }
          f = static_cast<double>(in) / (sub * sub * sub);
        }
        float& dst = (*frac)[v.linear_index(i, j, k)];
        dst = std::max(dst, static_cast<float>(f) * value);
      }
    }
  }
}

FluoroResult run_fluoro(const Options& o) {
  FluoroResult res;
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({.seed = 1});
  FluoroSpec spec;  // 512^2 at 0.4 mm, phantom 256 x 256 x 128 at 1.4 mm, CPU trilinear
  spec.projector.trilinear.threads = o.threads;
  res.detector = spec.c_arm.width;
  const auto t0 = std::chrono::steady_clock::now();
  FluoroscopyRenderer fr(tree, spec);
  res.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  // a wire through the LM into the LAD (~100 mm, 0.5 mm nodes) and a left injection at t = 0
  std::vector<Eigen::Vector3d> wire_m;
  for (const auto& p : tree.branches[tree.find("LM")].points) wire_m.push_back(p.position_m);
  const auto& lad = tree.branches[tree.find("LAD")].points;
  for (size_t i = 1; i < lad.size() && i < 160; ++i) wire_m.push_back(lad[i].position_m);
  const ContrastInjection inj{.start_s = 0, .duration_s = 2, .volume_ml = 8};
  const CArmPose pose{30, 20, Eigen::Vector3d::Zero()};
  FluoroFrame frame;
  const double t_frame = 1.2;  // the bolus in the distal branches, the LM full
  {
    const auto tb = std::chrono::steady_clock::now();
    fr.render({.time_s = t_frame, .pose = pose, .wire_m = wire_m, .injections = {&inj, 1}}, frame);
    res.background_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - tb).count();
  }
  // per frame with the pose unchanged: 15 fps pulses of the running bolus
  res.frames = o.quick ? 30 : 60;
  int n = 0;
  const auto ms = time_frames(1, res.frames, &res.frame_cpu_ms, [&] {
    fr.render({.time_s = 0.5 + (n++) / 15.0, .pose = pose, .wire_m = wire_m, .injections = {&inj, 1}}, frame);
  });
  res.frame_median_ms = percentile(ms, 0.5);
  res.frame_p99_ms = percentile(ms, 0.99);

  // the same frame, noiseless line integrals: cached background + overlays ...
  fr.render({.time_s = t_frame, .pose = pose, .wire_m = wire_m, .injections = {&inj, 1}}, frame);
  const Image overlay_line = fr.line_integrals();
  const DetectorGeometry g = frame.geometry;
  // ... vs the iodine and the wire voxelised into the same volume and all of it re-projected
  anatomy::ThoraxPhantomSpec ps;
  ps.seed = spec.seed;
  ps.dims = spec.volume_dims;
  ps.spacing_mm = spec.volume_spacing_mm;
  ps.contrast = false;
  const anatomy::Volume base = anatomy::make_thorax_phantom(ps, tree);
  anatomy::Volume vol = anatomy::Volume::make(base.dims, base.spacing_mm, base.origin_mm, anatomy::VoxelType::kFloat32);
  std::vector<float> frac(static_cast<size_t>(base.voxel_count()));
  const double hu_per_mu = 1000.0 / spec.projector.attenuation.mu_water_per_mm;
  const auto& segs = fr.contrast().segments();
  const auto& opacity = fr.contrast().segment_opacity();
  DrrRenderer full_drr(base, spec.projector);  // same projector and options; its volume is replaced below
  Image full_line;
  DetectorChain chain({.photons_per_pixel = spec.photons_per_pixel, .blur_sigma_px = spec.blur_sigma_px});
  chain.set_window(fr.window_lo(), fr.window_hi());
  Image counts;
  std::vector<uint16_t> full_pixels;
  {
    double chain_cpu_ms = 0;
    const auto cms = time_frames(1, 20, &chain_cpu_ms, [&] { chain.apply(overlay_line, 7, &counts, &full_pixels); });
    res.chain_median_ms = percentile(cms, 0.5);
  }
  res.full_frames = 3;
  std::vector<double> full_ms;
  for (int f = 0; f < res.full_frames; ++f) {
    const auto a0 = std::chrono::steady_clock::now();
    for (int64_t i = 0; i < base.voxel_count(); ++i) vol.hu_f32[i] = base.hu_i16[i];
    std::fill(frac.begin(), frac.end(), 0.0f);
    for (size_t i = 0; i < segs.size(); ++i) {
      if (opacity[i] < 1e-3) continue;
      voxelise_cone(vol, segs[i].a_mm, segs[i].b_mm, segs[i].ra_mm, segs[i].rb_mm,
                    static_cast<float>(hu_per_mu * spec.iodine_mu_per_mm * opacity[i]), 4, &frac);
    }
    for (int64_t i = 0; i < base.voxel_count(); ++i) vol.hu_f32[i] += frac[i];
    std::fill(frac.begin(), frac.end(), 0.0f);
    double from_tip_mm = 0;  // the tip coil as the renderer has it
    for (size_t i = wire_m.size(); i-- > 1;) {
      const double mu = from_tip_mm < spec.wire_tip_mm ? spec.wire_tip_mu_per_mm : spec.wire_mu_per_mm;
      from_tip_mm += 1000.0 * (wire_m[i] - wire_m[i - 1]).norm();
      voxelise_cone(vol, 1000.0 * wire_m[i - 1], 1000.0 * wire_m[i], spec.wire_radius_mm, spec.wire_radius_mm,
                    static_cast<float>(hu_per_mu * mu), 8, &frac);
    }
    for (int64_t i = 0; i < base.voxel_count(); ++i) vol.hu_f32[i] += frac[i];
    const auto a1 = std::chrono::steady_clock::now();
    DrrRenderer drr(vol, spec.projector);  // HU -> mu and bricks for the changed volume
    const auto a2 = std::chrono::steady_clock::now();
    drr.render(g, &full_line);
    const auto a3 = std::chrono::steady_clock::now();
    chain.apply(full_line, f, &counts, &full_pixels);
    const auto a4 = std::chrono::steady_clock::now();
    full_ms.push_back(std::chrono::duration<double, std::milli>(a4 - a0).count());
    res.full_voxelise_ms += std::chrono::duration<double, std::milli>(a1 - a0).count() / res.full_frames;
    res.full_mu_ms += std::chrono::duration<double, std::milli>(a2 - a1).count() / res.full_frames;
    res.full_project_ms += std::chrono::duration<double, std::milli>(a3 - a2).count() / res.full_frames;
  }
  res.full_median_ms = percentile(full_ms, 0.5);
  res.full_p99_ms = percentile(full_ms, 0.99);
  // errors: whole line integrals, and the added part alone (both minus the same background)
  Image background;
  full_drr.render(g, &background);
  double max_line = 0, max_add = 0, se = 0, se_add = 0, worst = 0, worst_add = 0;
  for (size_t i = 0; i < full_line.pixels.size(); ++i) {
    const double a = overlay_line.pixels[i], b = full_line.pixels[i], bg = background.pixels[i];
    max_line = std::max(max_line, b);
    max_add = std::max(max_add, b - bg);
    se += (a - b) * (a - b);
    worst = std::max(worst, std::abs(a - b));
  }
  const double npx = static_cast<double>(full_line.pixels.size());
  res.rmse_rel = std::sqrt(se / npx) / max_line;
  res.max_rel = worst / max_line;
  int n_add = 0;
  for (size_t i = 0; i < full_line.pixels.size(); ++i) {
    const double bg = background.pixels[i];
    const double a = overlay_line.pixels[i] - bg, b = full_line.pixels[i] - bg;
    if (std::max(a, b) < 1e-3 * max_add) continue;  // the footprint of iodine or wire
    se_add += (a - b) * (a - b);
    worst_add = std::max(worst_add, std::abs(a - b));
    ++n_add;
  }
  res.overlay_rmse_rel = n_add ? std::sqrt(se_add / n_add) / max_add : 0;
  res.overlay_max_rel = worst_add / max_add;
  std::printf(
      "xray: fluoro %d^2: build %.0f ms, background %.1f ms; frame median %.2f ms p99 %.2f ms (cpu %.2f, chain %.2f); "
      "full re-projection %.0f ms (voxelise %.0f, mu %.0f, project %.0f); rmse %.4f %% max %.3f %%; "
      "overlay part rmse %.2f %% max %.1f %%\n",
      res.detector, res.build_ms, res.background_ms, res.frame_median_ms, res.frame_p99_ms, res.frame_cpu_ms,
      res.chain_median_ms, res.full_median_ms, res.full_voxelise_ms, res.full_mu_ms, res.full_project_ms,
      100 * res.rmse_rel, 100 * res.max_rel, 100 * res.overlay_rmse_rel, 100 * res.overlay_max_rel);

  // example frames (16-bit grey, as the renderer makes them)
  auto png = [&](const std::string& name, const FluoroFrame& f) {
    std::string err;
    const std::string path = o.out_dir + "/" + name;
    if (write_png_gray16(f.width, f.height, f.pixels, path, &err)) {
      res.pngs.push_back(name);
    } else {
      std::printf("xray: %s not written: %s\n", name.c_str(), err.c_str());
    }
  };
  fr.render({.time_s = 1.6, .pose = pose, .wire_m = wire_m, .injections = {&inj, 1}}, frame);
  png("fluoro_lao30_cra20_contrast.png", frame);
  fr.render({.time_s = -1, .pose = pose, .wire_m = wire_m, .injections = {&inj, 1}}, frame);
  png("fluoro_lao30_cra20_wire.png", frame);
  FluoroFrame full_frame = frame;
  full_frame.pixels = full_pixels;
  png("fluoro_lao30_cra20_full_reprojection.png", full_frame);
  fr.render(
      {.time_s = 1.6, .pose = CArmPose{-30, -20, Eigen::Vector3d::Zero()}, .wire_m = wire_m, .injections = {&inj, 1}},
      frame);
  png("fluoro_rao30_cau20_contrast.png", frame);
  return res;
}

// pcisim's exact and trilinear projectors against plastimatch's exact one, same run (issue #36)
void write_plastimatch_section(std::ofstream& f, const PlastimatchRun& pm, const Row* exact, const Row* trilinear,
                               const Row* planes, int threads) {
  f << "\n## Against plastimatch (same run, same machine)\n\n";
  if (!pm.ran) {
    f << "Not run: " << pm.why << ".\n";
    return;
  }
  f << fmt::format(
      "`plastimatch drr -i exact` ({}) on the same 512^2 geometry: the volume's attenuation as pcisim computes it, "
      "written as a float MetaImage and projected with `-P none`, so both programs integrate the same values "
      "(plastimatch's own HU conversion differs: on the HU volume the two images correlated 0.989 in session 32's "
      "one-off check). Its time is what it prints as \"Total time\" for the image (after it has read the volume), "
      "median of {} runs; the whole process took {:.0f} ms (median), reading {:.0f} MiB of float mu included. "
      "pcisim ran on {} threads, plastimatch on its own (OpenMP: every core).\n\n",
      pm.version, pm.images, pm.process_ms, pm.volume_mib, threads);
  f << fmt::format(
      "Images: correlation {:.6f}; plastimatch's line integrals are in cm (scale {:.5f} to pcisim's mm); after "
      "that scale the RMSE is {:.4f} % of the largest line integral, {:.0f} % of the squared differences in the "
      "detector's first row.\n\n",
      pm.correlation, pm.scale, 100 * pm.rmse_rel, 100 * pm.first_row_share);
  f << "| projector | ms per 512^2 image | / plastimatch exact | target | met? |\n|---|---|---|---|---|\n";
  f << fmt::format("| plastimatch exact | {:.0f} | 1 | - | - |\n", pm.per_image_ms);
  if (exact) {
    const double ratio = exact->median_ms / pm.per_image_ms;
    f << fmt::format("| pcisim exact | {:.0f} | {:.2f} | <= 0.5 | {} |\n", exact->median_ms, ratio,
                     ratio <= 0.5 ? "yes" : "**no**");
  }
  if (trilinear)
    f << fmt::format("| pcisim trilinear, 1 voxel | {:.0f} | {:.2f} | <= 100 ms | {} |\n", trilinear->median_ms,
                     trilinear->median_ms / pm.per_image_ms, trilinear->median_ms <= 100 ? "yes" : "**no**");
  if (planes)
    f << fmt::format("| pcisim voxel planes (Joseph's method) | {:.0f} | {:.2f} | <= 100 ms | {} |\n",
                     planes->median_ms, planes->median_ms / pm.per_image_ms,
                     planes->median_ms <= 100 ? "yes" : "**no**");
}

void write_fluoro_section(std::ofstream& f, const FluoroResult& fl) {
  f << fmt::format(
      "\n## Fluoroscopy frames: cached background + analytic overlays vs full re-projection\n\n"
      "`FluoroscopyRenderer` at {0}^2 (0.4 mm pixels), default `FluoroSpec`: phantom 256 x 256 x 128 at "
      "1.4 mm with blood-filled lumens, CPU background one sample per voxel plane, 2000 quanta per pixel, "
      "blur sigma 0.7 px; LAO 30 / CRA 20; a ~90 mm wire (LM into the LAD, 0.5 mm nodes) and a left "
      "injection (8 ml over 2 s) running. Per frame (pose unchanged): copy of the cached background, "
      "iodine through every lumen segment holding contrast, the wire, Poisson noise, blur, log and window, "
      "single-threaded; median and p99 of {1} frames at 15 fps simulation times after one warm-up. "
      "Full re-projection: the same iodine (at the same opacities) and wire voxelised into a float copy of "
      "the volume (partial-volume fractions from 4^3 / 8^3 sub-samples per boundary voxel), HU to mu and "
      "bricks rebuilt, projected with the same projector, same image chain; {2} frames.\n\n",
      fl.detector, fl.frames, fl.full_frames);
  f << "| scheme | median ms | p99 ms | what |\n|---|---|---|---|\n";
  f << fmt::format(
      "| cached background + overlays | {:.2f} | {:.2f} | per frame; process CPU {:.2f} ms per frame; "
      "of which the image chain (noise, blur, log, window) {:.2f} ms median |\n",
      fl.frame_median_ms, fl.frame_p99_ms, fl.frame_cpu_ms, fl.chain_median_ms);
  f << fmt::format(
      "| full re-projection | {:.0f} | {:.0f} | voxelise {:.0f} + HU to mu {:.0f} + project {:.0f} ms, + image chain "
      "|\n",
      fl.full_median_ms, fl.full_p99_ms, fl.full_voxelise_ms, fl.full_mu_ms, fl.full_project_ms);
  f << fmt::format(
      "| background projection | {:.0f} | - | once per pose change (the first frame of a pose), all threads |\n",
      fl.background_ms);
  f << fmt::format("| renderer construction | {:.0f} | - | phantom + attenuation volume, once per scene |\n\n",
                   fl.build_ms);
  f << fmt::format(
      "Difference of the noiseless line integrals (same frame, t = 1.2 s): RMSE {:.4f} % and worst pixel "
      "{:.2f} % of the largest line integral; over the footprint of the iodine and the wire alone "
      "(both minus the same background), RMSE {:.1f} % and worst {:.0f} % of the largest added "
      "integral. The analytic chords are exact for the cone model; most of the difference is the "
      "voxelised side (a 0.36 mm wire and 1-2 mm lumens on 1.4 mm voxels, trilinear reads).\n\n",
      100 * fl.rmse_rel, 100 * fl.max_rel, 100 * fl.overlay_rmse_rel, 100 * fl.overlay_max_rel);
  const bool met = fl.frame_p99_ms < 1000.0 / 15;
  f << fmt::format(
      "Target: >= 15 frames/s at 512^2 on this machine without a GPU (per-frame work well under 60 ms): "
      "{:.1f} ms median, {:.1f} ms p99, i.e. {:.0f} frames/s from the median: **{}**.\n\n",
      fl.frame_median_ms, fl.frame_p99_ms, 1000.0 / fl.frame_median_ms, met ? "met" : "not met");
  if (!fl.pngs.empty()) {
    f << "Example frames (16-bit PNG as the renderer outputs them; LAO 30 / CRA 20 with contrast at t = 1.6 s, the "
         "wire alone, the full re-projection at t = 1.2 s, RAO 30 / CAU 20 with contrast):\n\n";
    for (const auto& name : fl.pngs) f << fmt::format("![{0}]({0}) ", name);
    f << "\n";
  }
}

#ifdef PCISIM_HAVE_CUDA
// the beating background's bins on the GPU (issue #14: a pose's bins within 50 ms): the phantom's
// heart and tree (heart_beat and vessel_motion at their defaults) sampled at 16 phases, the
// fluoroscopy's default background CT and detector; per pose, every bin's change projected (the
// GPU: full resolution, each change uploaded once; the CPU: half resolution, all threads) and
// added to the pose's static projection. Printed only (the GPU machine's run log keeps it).
void run_beating_gpu() {
  physics::WorldSpec ws;
  ws.heart_beat.emplace();
  ws.vessel_motion.emplace();
  const physics::World world(ws);
  const physics::BeatCycle cycle = world.sample_beat_cycle(16);
  const BeatSamples samples = beat_samples_from_m(cycle.rest_m, cycle.at_bin_m);
  const FluoroSpec spec;
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({.seed = ws.anatomy.seed});
  const anatomy::Volume ct = thorax_background(tree, spec);
  const AttenuationVolume mu(ct);
  CudaTrilinearProjector still_projector(mu, {.step_voxels = 1.0});
  for (const bool on_gpu : {true, false}) {
    BeatingBackgroundOptions o;
    o.gpu = on_gpu;
    o.change_stride = on_gpu ? 1 : 2;
    o.projector.step_voxels = 1.0;
    const auto b0 = std::chrono::steady_clock::now();
    BeatingBackground beat(mu, samples, o);
    const double build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - b0).count();
    std::vector<double> all_ms;
    for (int m = 0; m < 6; ++m) {
      const DetectorGeometry g = c_arm_geometry(spec.c_arm, CArmPose{30.0 + 3 * m, 20, Eigen::Vector3d::Zero()});
      Image still;
      still.resize(g.width, g.height);
      still_projector.project(g, &still);
      beat.set_pose(g, still);
      const auto t0 = std::chrono::steady_clock::now();
      while (beat.fill_ahead() > 0) {}
      if (m > 0)
        all_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    std::printf(
        "xray: beating background, a pose's 16 bins on the %s (change at %s resolution): median %.1f ms, p99 %.1f ms "
        "(wall, image copies included; %zu poses); built in %.0f ms\n",
        beat.on_gpu() ? "GPU" : "CPU", on_gpu ? "full" : "half", percentile(all_ms, 0.5), percentile(all_ms, 0.99),
        all_ms.size(), build_ms);
  }
  // what the cache replaces, on the GPU: every frame the CT warped at its phase (the box, on the
  // CPU), uploaded whole and projected
  const HeartWarp warp(mu, samples);
  AttenuationVolume work(ct);
  const DetectorGeometry g = c_arm_geometry(spec.c_arm, CArmPose{30, 20, Eigen::Vector3d::Zero()});
  Image img;
  img.resize(g.width, g.height);
  std::vector<double> warp_ms, upload_project_ms;
  for (int b = 0; b < 8; ++b) {
    const auto t0 = std::chrono::steady_clock::now();
    warp.write_warped(b, &work);
    const auto t1 = std::chrono::steady_clock::now();
    CudaTrilinearProjector per_frame(work, {.step_voxels = 1.0});
    per_frame.project(g, &img);
    const auto t2 = std::chrono::steady_clock::now();
    if (b == 0) continue;  // warm-up
    warp_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    upload_project_ms.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
  }
  std::printf(
      "xray: per-frame re-projection on the GPU: warp of the box (CPU, one thread) median %.1f ms, upload and "
      "projection median %.1f ms (p99 %.1f); %zu frames\n",
      percentile(warp_ms, 0.5), percentile(upload_project_ms, 0.5), percentile(upload_project_ms, 0.99),
      warp_ms.size());
}
#endif

int run(const std::vector<std::string>& args) {
  double slice_row_share = 0, slice_shared_share = 0;  // the voxel-plane packets' paths at 512^2
  Options o;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--quick") {
      o.quick = true;
    } else if (args[i] == "--fluoro-only") {
      o.fluoro_only = true;
    } else if (args[i] == "--out" && i + 1 < args.size()) {
      o.out_dir = args[++i];
    } else if (args[i] == "--threads" && i + 1 < args.size()) {
      o.threads = std::atoi(args[++i].c_str());
    } else if (args[i] == "--plastimatch" && i + 1 < args.size()) {
      o.plastimatch = args[++i];
    } else if (args[i] == "--plastimatch-images" && i + 1 < args.size()) {
      o.plastimatch_images = std::max(1, std::atoi(args[++i].c_str()));
    } else if (args[i] == "--plastimatch-only") {
      o.plastimatch_only = true;
    } else {
      std::printf(
          "pcisim-bench xray [--quick] [--fluoro-only] [--out DIR (docs/benchmarks)] [--threads N (all cores)]\n"
          "                  [--plastimatch PROGRAM|none (the first on PATH)] [--plastimatch-images N (5)]\n"
          "                  [--plastimatch-only]\n"
          "  full: 512^2 and 1024^2 detectors, steps 2, 1, 0.5, 0.25 voxel on CPU and GPU\n"
          "  --quick: CPU on 512^2 only with steps 1 and 0.5, fewer frames; the GPU sweep stays full\n"
          "  then fluoroscopy at 512^2: cached background + analytic overlays vs full re-projection\n"
          "  --fluoro-only: only that section, printed; writes its example PNGs, not xray.md/json\n"
          "  plastimatch (Debian package plastimatch), when installed: `plastimatch drr -i exact` on the same\n"
          "    volume and 512^2 geometry in the same run, its time per image (the median of N runs of the\n"
          "    \"Total time\" it prints) against pcisim's exact projector, and its image against pcisim's\n"
          "    (correlation, scale)\n"
          "  --plastimatch-only: only pcisim's exact 512^2 row and that comparison, printed\n");
      return args[i] == "--help" ? 0 : 2;
    }
  }
  if (o.plastimatch_only) o.quick = true;
  std::filesystem::create_directories(o.out_dir);
  const std::string machine = machine_info();
  std::printf("xray: %s\n", machine.c_str());

  if (o.fluoro_only) {
    run_fluoro(o);
    return 0;
  }
  const auto t0 = std::chrono::steady_clock::now();
  anatomy::ThoraxPhantomSpec spec;  // 512 x 512 x 256 at 0.7 mm, seed 1, iodine lumens
  const anatomy::Volume volume = anatomy::make_thorax_phantom(spec);
  const double phantom_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const auto t1 = std::chrono::steady_clock::now();
  const AttenuationVolume att(volume);
  const double mu_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
  std::printf("xray: phantom %.0f ms, attenuation volume %.0f ms\n", phantom_ms, mu_ms);

  const CArmPose pose{30, 20, Eigen::Vector3d::Zero()};  // LAO 30 CRA 20, isocentre at the heart
  const std::vector<int> detectors = o.quick ? std::vector<int>{512} : std::vector<int>{512, 1024};
  const std::vector<double> cpu_steps = o.quick ? std::vector<double>{1, 0.5} : std::vector<double>{2, 1, 0.5, 0.25};
  const std::vector<double> gpu_steps = {2, 1, 0.5, 0.25};
  const int cpu_frames = o.quick ? 3 : 5;
  std::vector<Row> rows;
  PlastimatchRun pm;
  std::string gpu_name;
  int cpu_threads = 0;

  SiddonProjector exact(att, o.threads);
  TrilinearProjector cpu(att, {.threads = o.threads});
#ifdef PCISIM_HAVE_CUDA
  std::unique_ptr<CudaTrilinearProjector> gpu;
  std::string why;
  if (CudaTrilinearProjector::available(&why)) {
    gpu = std::make_unique<CudaTrilinearProjector>(att);
    gpu_name = gpu->device_name();
  } else {
    std::printf("xray: GPU sweep skipped: %s\n", why.c_str());
  }
#endif
  cpu_threads = o.threads > 0 ? o.threads : static_cast<int>(std::thread::hardware_concurrency());

  for (const int n : detectors) {
    CArmSpec c;
    c.width = c.height = n;
    c.pixel_mm = 0.4 * 512.0 / n;  // the same 205 mm field on the detector
    const DetectorGeometry g = c_arm_geometry(c, pose);
    Image ref, img;
    ref.resize(n, n);
    img.resize(n, n);
    {
      Row r{"exact", n, 0};
      const auto ms = time_frames(1, cpu_frames, &r.cpu_ms, [&] { exact.project(g, &ref); });
      r.median_ms = percentile(ms, 0.5);
      r.p99_ms = percentile(ms, 0.99);
      r.frames = cpu_frames;
      rows.push_back(r);
      std::printf("xray: %4d^2 exact          %9.1f ms (p99 %.1f, cpu %.1f)\n", n, r.median_ms, r.p99_ms, r.cpu_ms);
    }
    if (n == 512 && o.plastimatch != "none") {
      const std::string program = o.plastimatch == "auto" ? find_plastimatch() : o.plastimatch;
      pm = run_plastimatch_drr(program, att, volume, c, pose, ref, o.out_dir + "/.plastimatch-work",
                               o.plastimatch_images);
      if (pm.ran) {
        std::printf(
            "xray: %4d^2 plastimatch exact %6.1f ms an image (median of %d; its process %.0f ms); correlation with "
            "pcisim's exact %.6f, scale %.6g, RMSE after it %.4f %% of max\n",
            n, pm.per_image_ms, pm.images, pm.process_ms, pm.correlation, pm.scale, 100 * pm.rmse_rel);
      } else {
        std::printf("xray: plastimatch comparison skipped: %s\n", pm.why.c_str());
      }
      std::filesystem::remove_all(o.out_dir + "/.plastimatch-work");  // 256 MiB of mu
    }
    if (o.plastimatch_only) return pm.ran ? 0 : 1;
    const bool cpu_here = !o.quick || n == 512;
    // one CPU trilinear row: the marcher with `options`, timed, compared with exact
    auto cpu_row = [&](const char* name, const TrilinearOptions& options) {
      cpu.set_options(options);
      Row r{name, n, options.step_voxels};
      const auto ms = time_frames(1, cpu_frames, &r.cpu_ms, [&] { cpu.project(g, &img); });
      r.median_ms = percentile(ms, 0.5);
      r.p99_ms = percentile(ms, 0.99);
      r.frames = cpu_frames;
      errors(img, ref, &r);
      rows.push_back(r);
      std::printf("xray: %4d^2 %-8s step %.2f %9.1f ms (p99 %.1f, cpu %.1f)  rmse %.4f %%  max %.4f %%\n", n, name,
                  options.step_voxels, r.median_ms, r.p99_ms, r.cpu_ms, 100 * r.rmse_rel, 100 * r.max_rel);
    };
    for (const double step : cpu_steps) {
      if (!cpu_here) break;
      cpu_row("cpu", {.step_voxels = step, .skip_empty = true});
    }
    // the same marcher one ray at a time (no AVX2 packets), at 1 voxel: the packets' gain in this run
    if (cpu_here) cpu_row("cpu-1ray", {.step_voxels = 1.0, .skip_empty = true, .packets = false});
    // Joseph's method: one sample per voxel plane of the ray's major axis, bilinear in the plane
    // (issue #36 item 3), with packets and one ray at a time; its step is the planes' (shown as 1)
    if (cpu_here) {
      const ray::SlicePacketCounts before = ray::slice_packet_counts();
      cpu_row("cpu-slices", {.step_voxels = 1.0, .skip_empty = true, .slices = true});
      const ray::SlicePacketCounts after = ray::slice_packet_counts();
      const double steps = double(after.row_steps - before.row_steps + after.gathered_steps - before.gathered_steps);
      const double packets = double(after.shared_walks - before.shared_walks + after.lane_walks - before.lane_walks);
      if (n == 512 && steps > 0 && packets > 0) {
        slice_row_share = (after.row_steps - before.row_steps) / steps;
        slice_shared_share = (after.shared_walks - before.shared_walks) / packets;
      }
      cpu_row("cpu-slices-1ray", {.step_voxels = 1.0, .skip_empty = true, .packets = false, .slices = true});
    }
#ifdef PCISIM_HAVE_OSMESA
    // the OSMesa GL projector (software GL here: Mesa llvmpipe), same steps as the CPU marcher
    for (const double step : cpu_steps) {
      if (!cpu_here) break;
      std::string why;
      if (!gl_projector_available(&why)) {
        std::printf("xray: GL sweep skipped: %s\n", why.c_str());
        break;
      }
      GlProjector gl(att, step);
      Row r{"gl", n, step};
      const auto ms = time_frames(1, cpu_frames, &r.cpu_ms, [&] { gl.project(g, &img); });
      r.median_ms = percentile(ms, 0.5);
      r.p99_ms = percentile(ms, 0.99);
      r.frames = cpu_frames;
      errors(img, ref, &r);
      rows.push_back(r);
      std::printf("xray: %4d^2 gl   step %.2f %9.1f ms (p99 %.1f, cpu %.1f)  rmse %.4f %%  max %.4f %%\n", n, step,
                  r.median_ms, r.p99_ms, r.cpu_ms, 100 * r.rmse_rel, 100 * r.max_rel);
    }
#endif
#ifdef PCISIM_HAVE_CUDA
    // the twin (ray::trilinear on global memory), the texture unit's filter on the same samples,
    // and Joseph's method (the CPU's ray::slice_ray; one sample a plane: shown at step 1)
    enum Read { kTwin, kTexture, kSlices };
    for (const Read read : {kTwin, kTexture, kSlices}) {
      if (!gpu) break;
      const std::vector<double> steps = read == kSlices ? std::vector<double>{1.0} : gpu_steps;
      for (const double step : steps) {
        gpu->set_options(
            {.step_voxels = step, .skip_empty = true, .texture = read == kTexture, .slices = read == kSlices});
        gpu->project(g, &img);  // the image for the error; also a warm-up
        Row r{read == kTexture ? "cuda-tex" : read == kSlices ? "cuda-slices" : "cuda", n, step};
        const int runs = o.quick ? 100 : 200;
        const auto ms_f = gpu->time_kernel_ms(g, 10, runs);
        const std::vector<double> ms(ms_f.begin(), ms_f.end());
        r.median_ms = percentile(ms, 0.5);
        r.p99_ms = percentile(ms, 0.99);
        r.frames = runs;
        errors(img, ref, &r);
        rows.push_back(r);
        std::printf("xray: %4d^2 %s step %.2f %9.3f ms (p99 %.3f)  rmse %.4f %%  max %.4f %%\n", n, r.projector.c_str(),
                    step, r.median_ms, r.p99_ms, 100 * r.rmse_rel, 100 * r.max_rel);
      }
    }
#endif
  }

  const FluoroResult fl = run_fluoro(o);
#ifdef PCISIM_HAVE_CUDA
  if (gpu) run_beating_gpu();
#endif

  // json
  {
    std::ofstream f(o.out_dir + "/xray.json");
    f << "{\n"
      << fmt::format("  \"machine\": \"{}\",\n  \"gpu\": \"{}\",\n  \"cpu_threads\": {},\n", machine, gpu_name,
                     cpu_threads);
    f << fmt::format(
        "  \"quick\": {},\n  \"phantom\": {{\"dims\": [512, 512, 256], \"spacing_mm\": 0.7, \"seed\": 1, "
        "\"build_ms\": {:.1f}, \"attenuation_ms\": {:.1f}}},\n",
        o.quick, phantom_ms, mu_ms);
    f << "  \"c_arm\": {\"primary_deg\": 30, \"secondary_deg\": 20, \"sid_mm\": 1100, \"sad_mm\": 750, "
         "\"field_mm\": 204.8},\n  \"rows\": [\n";
    for (size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      f << fmt::format(
          "    {{\"projector\": \"{}\", \"detector\": {}, \"step_voxels\": {}, \"median_ms\": {:.4f}, "
          "\"p99_ms\": {:.4f}, \"cpu_ms\": {:.2f}, \"frames\": {}, \"rmse_rel\": {:.6g}, \"max_rel\": {:.6g}}}{}\n",
          r.projector, r.detector, r.step, r.median_ms, r.p99_ms, r.cpu_ms, r.frames, r.rmse_rel, r.max_rel,
          i + 1 < rows.size() ? "," : "");
    }
    f << "  ],\n";
    if (pm.ran) {
      f << fmt::format(
          "  \"plastimatch\": {{\"version\": \"{}\", \"detector\": 512, \"images\": {}, \"exact_ms\": {:.2f}, "
          "\"process_ms\": {:.1f}, \"correlation\": {:.8f}, \"scale\": {:.6g}, \"rmse_rel\": {:.6g}, "
          "\"first_row_share\": {:.4f}}},\n",
          pm.version, pm.images, pm.per_image_ms, pm.process_ms, pm.correlation, pm.scale, pm.rmse_rel,
          pm.first_row_share);
    } else {
      f << "  \"plastimatch\": null,\n";
    }
    f << fmt::format(
        "  \"fluoro\": {{\"detector\": {}, \"frames\": {}, \"build_ms\": {:.1f}, \"background_ms\": {:.2f}, "
        "\"frame_median_ms\": {:.3f}, \"frame_p99_ms\": {:.3f}, \"frame_cpu_ms\": {:.3f}, \"chain_median_ms\": {:.3f}, "
        "\"full_median_ms\": {:.1f}, \"full_p99_ms\": {:.1f}, \"full_frames\": {}, \"full_voxelise_ms\": {:.1f}, "
        "\"full_mu_ms\": {:.1f}, \"full_project_ms\": {:.1f}, \"rmse_rel\": {:.6g}, \"max_rel\": {:.6g}, "
        "\"overlay_rmse_rel\": {:.6g}, \"overlay_max_rel\": {:.6g}}}\n",
        fl.detector, fl.frames, fl.build_ms, fl.background_ms, fl.frame_median_ms, fl.frame_p99_ms, fl.frame_cpu_ms,
        fl.chain_median_ms, fl.full_median_ms, fl.full_p99_ms, fl.full_frames, fl.full_voxelise_ms, fl.full_mu_ms,
        fl.full_project_ms, fl.rmse_rel, fl.max_rel, fl.overlay_rmse_rel, fl.overlay_max_rel);
    f << "}\n";
  }
  // markdown
  {
    std::ofstream f(o.out_dir + "/xray.md");
    f << "# X-ray projection (DRR) benchmark\n\n";
    f << fmt::format("Generated by `pcisim-bench xray{}` on {}; {} CPU threads{}.\n\n", o.quick ? " --quick" : "",
                     machine, cpu_threads, gpu_name.empty() ? "; no GPU" : "; GPU: " + gpu_name);
    f << "Phantom: seeded thorax (seed 1), 512 x 512 x 256 voxels at 0.7 mm, iodine lumens at 400 HU "
      << fmt::format("(built in {:.0f} ms; HU to mu in {:.0f} ms). ", phantom_ms, mu_ms)
      << "C-arm LAO 30 / CRA 20, SID 1100 mm, SAD 750 mm, isocentre at the heart centre; 512^2 detector at 0.4 mm, "
         "1024^2 at 0.2 mm (same field). mu_water 0.02 /mm, HU < -800 is air.\n\n";
    f << "Errors are against the exact (Siddon) projection of the same geometry: RMSE and worst pixel, relative to the "
         "largest exact line integral. CPU times: wall clock per frame, median and p99 of "
      << cpu_frames
      << " frames after one warm-up (p99 of so few frames is their maximum), and the process CPU time "
         "per frame (wall x threads when nothing else runs; more wall than that means the cores were shared). "
         "GPU times: kernel only, "
         "CUDA events, median and p99 of 100-200 launches after 10 warm-up launches.\n\n";
    f << "| projector | detector | step (voxel) | median ms | p99 ms | CPU ms (all threads) | RMSE % of max | max % of "
         "max |\n";
    f << "|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows) {
      f << fmt::format("| {} | {}^2 | {} | {:.3f} | {:.3f} | {} | {} | {} |\n", r.projector, r.detector,
                       r.projector == "exact" ? std::string("-") : fmt::format("{}", r.step), r.median_ms, r.p99_ms,
                       r.projector.rfind("cuda", 0) == 0 ? std::string("-") : fmt::format("{:.0f}", r.cpu_ms),
                       r.projector == "exact" ? std::string("(reference)") : fmt::format("{:.4f}", 100 * r.rmse_rel),
                       r.projector == "exact" ? std::string("-") : fmt::format("{:.4f}", 100 * r.max_rel));
    }
    f << "\n![error vs time](xray.png)\n";
    // issue #14's projection targets, for the 512^2 DRR of this phantom on this machine
    auto find = [&](const std::string& p, double step) -> const Row* {
      for (const Row& r : rows)
        if (r.projector == p && r.detector == 512 && (p == "exact" || r.step == step)) return &r;
      return nullptr;
    };
    const Row* tri = find("cpu", 1.0);
    const Row* one = find("cpu-1ray", 1.0);
    const Row* ex = find("exact", 0);
    if (tri && ex) {
      f << "\nIssue #14's targets for the 512^2 DRR (this machine, 2 threads):\n\n| target | measured | met? |\n"
           "|---|---|---|\n";
      f << fmt::format("| trilinear at 1 voxel <= 100 ms, same error | {:.0f} ms median ({:.4f} % RMSE){} | {} |\n",
                       tri->median_ms, 100 * tri->rmse_rel,
                       one ? fmt::format("; one ray at a time {:.0f} ms in this run", one->median_ms) : std::string(),
                       tri->median_ms <= 100 ? "yes" : "**no**");
      if (const Row* planes = find("cpu-slices", 1.0))
        f << fmt::format(
            "| the same at no more error, one sample per voxel plane (Joseph's method, the scenes' CPU projector; "
            "{:.2f} % of its packets' steps read whole rows, {:.1f} % of its packets walked the bricks once for eight) "
            "<= 100 ms | {:.0f} ms median ({:.4f} % RMSE) | {} |\n",
            100 * slice_row_share, 100 * slice_shared_share, planes->median_ms, 100 * planes->rmse_rel,
            planes->median_ms <= 100 && planes->rmse_rel <= tri->rmse_rel ? "yes" : "**no**");
      f << fmt::format("| exact <= 200 ms | {:.0f} ms median | {} |\n", ex->median_ms,
                       ex->median_ms <= 200 ? "yes" : "**no**");
    }
    const Row* twin = find("cuda", 1.0);
    const Row* tex = find("cuda-tex", 1.0);
    if (twin && tex) {
      f << "\nIssue #36's GPU target for the 512^2 DRR at 1 voxel (kernel only, " << gpu_name << "):\n\n"
        << "| target | twin (ray::trilinear) | texture unit's filter | met? |\n|---|---|---|---|\n";
      f << fmt::format("| <= 0.5 ms | {:.3f} ms ({:.4f} % RMSE) | {:.3f} ms ({:.4f} % RMSE) | {} |\n", twin->median_ms,
                       100 * twin->rmse_rel, tex->median_ms, 100 * tex->rmse_rel,
                       std::min(twin->median_ms, tex->median_ms) <= 0.5 ? "yes" : "**no**");
    }
    write_plastimatch_section(f, pm, find("exact", 0), tri, find("cpu-slices", 1.0), cpu_threads);
    write_fluoro_section(f, fl);
    // hand-kept notes and the GPU machine's figures from earlier runs, appended unchanged
    std::ifstream earlier(o.out_dir + "/xray.earlier.md");
    if (earlier) f << "\n" << earlier.rdbuf();
  }
  const std::string script = std::filesystem::exists("docs/benchmarks/xray.py") ? "docs/benchmarks/xray.py" : "";
  if (!script.empty()) {
    const std::string cmd = fmt::format("/usr/bin/python3 {} {} > /dev/null 2>&1", script, o.out_dir);
    if (std::system(cmd.c_str()) != 0) std::printf("xray: plot skipped (python3-matplotlib missing?)\n");
  } else {
    std::printf("xray: plot skipped (run from the repository root to find docs/benchmarks/xray.py)\n");
  }
  std::printf("xray: wrote %s/xray.md and xray.json\n", o.out_dir.c_str());
  return 0;
}

const bool registered = add("xray", "DRR projectors: ms per frame and error vs exact Siddon, CPU and GPU", run);

}  // namespace
}  // namespace pcisim::bench
