// pcisim-bench pbd-gpu: what the CUDA Jacobi PBD step (SolverKind::kJacobiCuda) buys over the
// CPU Jacobi step (SolverKind::kJacobi, one thread) on the procedural ventricle at three lattice
// spacings (~1k, ~10k, ~50k particles; 12 mm clusters, springs to face and edge neighbours, the
// septal side driven by a beat), with the heart's knobs (2 substeps x 6 iterations, SOR 1.5, per-
// particle averaging, damping 5/s) at 30 Hz. Per body: wall ms per PbdSystem::step, median and
// p99 (nearest rank) after warm-up steps, for both; for the GPU also its CUDA-event split (upload,
// kernels as one graph, download), and the largest CPU-GPU position difference over the run
// (the two step the same driven body side by side). Writes pbd-gpu.md into docs/benchmarks/ or
// --out DIR. Without a CUDA device it times the CPU alone and says so.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <fstream>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "bench/bench_options.h"
#include "bench/bench_registry.h"
#include "bench/bench_stats.h"
#include "bench/machine_info.h"
#include "physics/pbd/pbd_cuda_solver.h"
#include "physics/pbd/procedural_ventricle.h"
#include "physics/soft_tissue/tissue_body.h"
#include "physics/soft_tissue/tissue_model.h"
#include "anatomy/organ/kidney_phantom.h"

namespace pcisim::bench {
namespace {

using namespace pcisim::physics::pbd;

constexpr double kDtS = 1.0 / 30.0;

struct Body {
  const char* name;
  double spacing_m;
};
// spacings picked for about 1k, 10k and 50k particles
constexpr Body kBodies[] = {{"~1k", 0.0045}, {"~10k", 0.0021}, {"~50k", 0.00125}};

struct Row {
  std::string name;
  double spacing_mm = 0;
  int particles = 0, distances = 0, clusters = 0, slots = 0, steps = 0;
  double cpu_median_ms = 0, cpu_p99_ms = 0;
  std::optional<double> gpu_median_ms, gpu_p99_ms, kernels_median_ms, kernels_p99_ms, upload_median_ms,
      download_median_ms, max_gap_m;
};

Eigen::Vector3d beat(const Eigen::Vector3d& rest_m, double t_s) {
  const double s = 0.15 * 0.5 * (1.0 - std::cos(2.0 * std::numbers::pi * 1.2 * t_s));
  return {rest_m.x() * (1.0 - s), rest_m.y() * (1.0 - s), rest_m.z() + 0.05 * s * std::abs(rest_m.z())};
}

PbdParams params(SolverKind solver) {
  PbdParams p;
  p.substeps = 2;
  p.iterations = 6;
  p.solver = solver;
  p.sor_w = 1.5;
  p.damping_per_s = 5.0;
  return p;
}

double ms_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// times two copies of one system side by side, `drive` editing each before its step
Row time_pair(PbdSystem& cpu, PbdSystem* dev, const PbdParams& cpu_params, const PbdParams& dev_params, double dt_s,
              int warmup, int steps, const std::function<void(PbdSystem&, int)>& drive) {
  Row r;
  r.particles = cpu.particle_count();
  r.distances = static_cast<int>(cpu.distance_constraints().size());
  r.clusters = cpu.clusters().count();
  r.slots = cpu.clusters().slot_count();
  r.steps = steps;
  std::vector<double> cpu_ms, gpu_ms, kernels_ms, upload_ms, download_ms;
  double gap = 0.0;
  for (int k = 1; k <= warmup + steps; ++k) {
    drive(cpu, k);
    const auto t0 = std::chrono::steady_clock::now();
    cpu.step(dt_s, cpu_params);
    const auto t1 = std::chrono::steady_clock::now();
    if (k > warmup) cpu_ms.push_back(ms_between(t0, t1));
    if (!dev) continue;
    drive(*dev, k);
    const auto g0 = std::chrono::steady_clock::now();
    dev->step(dt_s, dev_params);
    const auto g1 = std::chrono::steady_clock::now();
    gap = std::max(gap, (cpu.particles().position_m - dev->particles().position_m).colwise().norm().maxCoeff());
    if (k <= warmup) continue;
    const PbdCudaStepTimings& t = dev->cuda_solver()->last_timings();
    gpu_ms.push_back(ms_between(g0, g1));
    kernels_ms.push_back(t.kernels_ms);
    upload_ms.push_back(t.upload_ms);
    download_ms.push_back(t.download_ms);
  }
  r.cpu_median_ms = percentile(cpu_ms, 0.5);
  r.cpu_p99_ms = percentile(cpu_ms, 0.99);
  if (dev) {
    r.gpu_median_ms = percentile(gpu_ms, 0.5);
    r.gpu_p99_ms = percentile(gpu_ms, 0.99);
    r.kernels_median_ms = percentile(kernels_ms, 0.5);
    r.kernels_p99_ms = percentile(kernels_ms, 0.99);
    r.upload_median_ms = percentile(upload_ms, 0.5);
    r.download_median_ms = percentile(download_ms, 0.5);
    r.max_gap_m = gap;
  }
  return r;
}

Row run(const Body& b, int warmup, int steps, bool gpu) {
  VentricleSpec spec;
  spec.spacing_m = b.spacing_m;
  Ventricle cpu = build_ventricle(spec);
  std::optional<Ventricle> dev;
  if (gpu) dev.emplace(build_ventricle(spec));
  Row r = time_pair(cpu.system, dev ? &dev->system : nullptr, params(SolverKind::kJacobi),
                    params(SolverKind::kJacobiCuda), kDtS, warmup, steps, [&](PbdSystem& s, int k) {
                      Ventricle& v = &s == &cpu.system ? cpu : *dev;  // each copy drives its own targets
                      for (int i : v.driven) v.system.set_driven_target(i, beat(v.rest_m.col(i), k * kDtS));
                    });
  r.name = b.name;
  r.spacing_mm = b.spacing_m * 1e3;
  return r;
}

// the soft-tissue kidney's particle model (physics/soft_tissue) at the scene's knobs with the
// Jacobi solver and without the clusters' volume (the CUDA solver has none) (3 substeps x 9 iterations, SOR 1.5,
// compliance 2e-5 s^2, damping 12/s, 30 Hz): its clusters only, released from a 15 % squash along y with no gravity.
// The scene's contacts (support and probe) are projected on the CPU only and are not part of this step
Row run_kidney(double radius_mm, int warmup, int steps, bool gpu) {
  namespace st = pcisim::physics::soft_tissue;
  anatomy::KidneySpec k;
  k.ct_spacing_mm = 4.0;  // the CT is not used
  const anatomy::Organ organ = anatomy::kidney_organ(anatomy::make_kidney_phantom(k));
  st::TissueModelSpec spec;
  spec.particle_radius_m = radius_mm * 1e-3;
  const st::TissueModel model = st::build_tissue_model(organ.surface, organ.fiducials_m, spec);
  st::TissueParams tp;
  tp.solver = SolverKind::kJacobi;
  tp.sor_w = 1.5;
  tp.gravity_m_per_s2 = Eigen::Vector3d::Zero();
  const st::TissueBody body(model, tp, {organ.support_normal, organ.support_offset_m - 1.0});
  PbdSystem cpu = body.system();
  std::optional<PbdSystem> dev;
  if (gpu) dev.emplace(body.system());
  PbdParams p;
  p.substeps = tp.substeps;
  p.iterations = tp.iterations;
  p.solver = SolverKind::kJacobi;
  p.sor_w = tp.sor_w;
  p.damping_per_s = tp.damping_per_s;
  p.gravity_m_per_s2 = Eigen::Vector3d::Zero();
  PbdParams pd = p;
  pd.solver = SolverKind::kJacobiCuda;
  for (PbdSystem* s : {&cpu, dev ? &*dev : nullptr})
    if (s) s->particles().position_m.row(1) *= 0.85;
  Row r = time_pair(cpu, dev ? &*dev : nullptr, p, pd, kDtS, warmup, steps, [](PbdSystem&, int) {});
  r.name = fmt::format("kidney r {} mm", radius_mm);
  r.spacing_mm = radius_mm;
  return r;
}

std::string opt(const std::optional<double>& v, const char* format = "{:.3f}") {
  return v ? fmt::format(fmt::runtime(format), *v) : std::string("—");
}

constexpr const char* kUsage =
    "usage: pcisim-bench pbd-gpu [--quick] [--out DIR]\n"
    "  CPU Jacobi vs CUDA Jacobi ms per PBD step on the procedural ventricle (~1k, ~10k, ~50k particles);\n"
    "  --quick: 5 warm-up + 20 timed steps per body instead of 10 + 100\n";

int run_bench(const std::vector<std::string>& args) {
  BenchOptions o;
  if (const int rc = parse_bench_options(args, "pbd-gpu", kUsage, &o); rc >= 0) return rc;
  const bool quick = o.quick;
  const std::string out_dir = o.out_dir;
  const int warmup = quick ? 5 : 10, steps = quick ? 20 : 100;
  std::string why;
  const bool gpu = pbd_cuda_available(&why);
  const std::string device = gpu ? pbd_cuda_device_name() : "none (" + why + ")";
  const std::string machine = machine_info();
  std::printf("pbd-gpu: %s; GPU: %s\n", machine.c_str(), device.c_str());
  std::vector<Row> rows;
  auto timed = [&](Row row) {
    rows.push_back(std::move(row));
    const Row& r = rows.back();
    std::printf(
        "pbd-gpu: %-5s %6d particles: CPU median %.3f p99 %.3f ms | CUDA median %s p99 %s ms (kernels %s, up %s, down "
        "%s) | max gap %s m\n",
        r.name.c_str(), r.particles, r.cpu_median_ms, r.cpu_p99_ms, opt(r.gpu_median_ms).c_str(),
        opt(r.gpu_p99_ms).c_str(), opt(r.kernels_median_ms).c_str(), opt(r.upload_median_ms).c_str(),
        opt(r.download_median_ms).c_str(), opt(r.max_gap_m, "{:.2g}").c_str());
  };
  for (const Body& b : kBodies) timed(run(b, warmup, steps, gpu));
  const size_t ventricles = rows.size();
  for (double radius_mm : {3.3, 2.2}) timed(run_kidney(radius_mm, warmup, steps, gpu));
  std::filesystem::create_directories(out_dir);
  std::ofstream f(std::filesystem::path(out_dir) / "pbd-gpu.md");
  f << "# PBD step: CPU Jacobi vs CUDA Jacobi\n\n";
  f << fmt::format("Generated by `pcisim-bench pbd-gpu{}` on {}; GPU: **{}**.\n\n", quick ? " --quick" : "", machine,
                   device);
  f << "Procedural ventricle (`physics/pbd/procedural_ventricle.h`) at three lattice spacings, 12 mm clusters "
       "(25 % overlap), springs to face and edge neighbours, septal side driven by a beat; the heart's knobs: "
       "2 substeps × 6 iterations, Jacobi SOR w = 1.5, per-particle averaging, damping 5/s, 30 Hz. Wall ms per "
       "`PbdSystem::step` (steady clock), "
    << fmt::format("{} timed steps after {} warm-up steps, median and p99 (nearest rank). ", steps, warmup)
    << "CPU: `SolverKind::kJacobi`, one thread. CUDA: `SolverKind::kJacobiCuda`, double precision, the whole "
       "step as one CUDA graph; its wall time includes uploading positions, velocities, states, targets and "
       "cluster rotations and downloading them again (pageable memory), split by CUDA events. The two bodies "
       "are stepped side by side; *gap* is the largest distance of a particle between them over the run.\n\n";
  auto table = [&](size_t from, size_t to) {
    f << "| body | spacing mm | particles | springs | clusters | cluster slots | CPU median ms | CPU p99 ms | CUDA "
         "median ms | CUDA p99 ms | speed-up (median) | kernels median ms | kernels p99 ms | upload ms | download ms "
         "| gap m |\n";
    f << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (size_t i = from; i < to; ++i) {
      const Row& r = rows[i];
      f << fmt::format(
          "| {} | {:.2f} | {} | {} | {} | {} | {:.3f} | {:.3f} | {} | {} | {} | {} | {} | {} | {} | {} |\n", r.name,
          r.spacing_mm, r.particles, r.distances, r.clusters, r.slots, r.cpu_median_ms, r.cpu_p99_ms,
          opt(r.gpu_median_ms), opt(r.gpu_p99_ms),
          r.gpu_median_ms ? fmt::format("{:.1f}×", r.cpu_median_ms / *r.gpu_median_ms) : std::string("—"),
          opt(r.kernels_median_ms), opt(r.kernels_p99_ms), opt(r.upload_median_ms), opt(r.download_median_ms),
          opt(r.max_gap_m, "{:.2g}"));
    }
  };
  table(0, ventricles);
  f << "\n## The soft-tissue kidney\n\n"
       "The kidney's particle model (`physics/soft_tissue`, issue #16) at the paper's particle radii 3.3 and 2.2 mm "
       "(spacing column: the radius), with `scenes/kidney.json`'s knobs but the Jacobi solver and no volume constraint "
       "(the CUDA "
       "solver has none): 3 substeps × 9 iterations, SOR w = 1.5, cluster compliance 2e-5 s², damping 12/s, 30 Hz "
       "steps. Its clusters only, "
       "released from a 15 % squash along y without gravity; the scene's support and probe contacts are projected "
       "on the CPU only (`kJacobiCuda` is refused with contacts) and are not in these times. The scene's whole "
       "step, contacts included, is timed by `pcisim-bench soft-tissue` (docs/benchmarks/soft-tissue.md).\n\n";
  table(ventricles, rows.size());
  if (!gpu) f << "\nNo CUDA device was usable here, so only the CPU was timed.\n";
  std::printf("pbd-gpu: wrote %s\n", (std::filesystem::path(out_dir) / "pbd-gpu.md").c_str());
  return 0;
}

const bool registered =
    add("pbd-gpu", "CPU vs CUDA Jacobi PBD ms per step on ~1k/10k/50k-particle ventricles", run_bench);

}  // namespace
}  // namespace pcisim::bench
