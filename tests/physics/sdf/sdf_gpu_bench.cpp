// SDF build and query timings, CPU twin vs CUDA twin, on the phantom lumen. Built and run by
// scripts/gpu-check (not part of the test suite: it measures, the tests assert). Markdown out.
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "physics/sdf/signed_distance_field.h"
#include "physics/sdf/signed_distance_field_cuda.h"
#include "anatomy/phantom/coronary_phantom.h"
#include "anatomy/vessel/lumen_mesh.h"

using namespace pcisim::physics;
namespace anatomy = pcisim::anatomy;
using Clock = std::chrono::steady_clock;

static double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
static double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

int main() {
  std::string why;
  if (!cuda_sdf_available(&why)) {
    std::printf("no GPU: %s\n", why.c_str());
    return 0;
  }
  cudaDeviceProp prop{};
  cudaGetDeviceProperties(&prop, 0);
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({});
  const anatomy::TriangleMesh lumen = anatomy::loft_lumen(tree, {});
  std::printf(
      "# SDF build and query, CPU twin vs CUDA twin\n\nGPU: %s (sm_%d%d). Host CPU: 1 thread. Phantom seed 1, "
      "lumen incl. aorta, %zu triangles, band 4 cells, padding 1 mm.\n\n",
      prop.name, prop.major, prop.minor, lumen.triangles.size());
  std::printf(
      "| spacing | grid points (virtual) | bricks stored | memory | CPU build ms | GPU build ms (wall) | "
      "GPU kernels ms | plan ms | transfer ms | remainder ms | max abs diff CPU-GPU |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (double h : {0.4e-3, 0.2e-3, 0.1e-3}) {
    SdfBuildSpec spec;
    spec.spacing_m = h;
    std::vector<double> cpu_ms, gpu_ms, kern, plan, transfer, rem;
    SignedDistanceField cpu, gpu;
    const int cpu_runs = h < 0.15e-3 ? 1 : 3;
    for (int r = 0; r < cpu_runs; ++r) {
      auto t0 = Clock::now();
      cpu = SignedDistanceField::build(lumen, spec);
      cpu_ms.push_back(ms_since(t0));
    }
    build_sdf_cuda(lumen, spec);  // warm-up (context, allocations)
    for (int r = 0; r < 5; ++r) {
      CudaSdfBuildTimings t;
      auto t0 = Clock::now();
      gpu = build_sdf_cuda(lumen, spec, &t);
      gpu_ms.push_back(ms_since(t0));
      kern.push_back(t.kernels_ms), plan.push_back(t.plan_ms), transfer.push_back(t.transfer_ms),
          rem.push_back(t.remainder_ms);
    }
    double worst = 0;
    for (size_t i = 0; i < cpu.values_m().size(); ++i)
      worst = std::max(worst, double(std::abs(cpu.values_m()[i] - gpu.values_m()[i])));
    const double points = double(cpu.dims().x()) * cpu.dims().y() * cpu.dims().z();
    std::printf("| %.1f mm | %.0fM | %zu | %.1f MB | %.0f | %.0f | %.1f | %.0f | %.0f | %.0f | %.2g m |\n", h * 1e3,
                points / 1e6, cpu.values_m().size() / 512, cpu.memory_bytes() / 1e6, median(cpu_ms), median(gpu_ms),
                median(kern), median(plan), median(transfer), median(rem), worst);
  }

  // queries: points jittered about the centerlines (real data, not zeros)
  const SignedDistanceField field = SignedDistanceField::build(lumen, 0.2e-3, 1e-3);
  const int n = 1 << 20;
  std::vector<Eigen::Vector3d> pts(n);
  std::vector<double> xyz(3 * size_t(n));
  std::mt19937 rng(1);
  std::normal_distribution<double> jitter(0.0, 1.0e-3);
  std::vector<const anatomy::CenterlinePoint*> all;
  for (const auto& b : tree.branches)
    for (const auto& p : b.points) all.push_back(&p);
  for (int i = 0; i < n; ++i) {
    pts[i] = all[i % all.size()]->position_m + Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng));
    for (int a = 0; a < 3; ++a) xyz[3 * size_t(i) + a] = pts[i][a];
  }
  std::vector<SdfSample> cpu_out(n);
  std::vector<double> cpu_q;
  for (int r = 0; r < 3; ++r) {
    auto t0 = Clock::now();
    field.sample_many(pts.data(), n, cpu_out.data());
    cpu_q.push_back(ms_since(t0));
  }
  CudaSdfSampler sampler(field);
  double *d_p, *d_d, *d_g;
  uint8_t* d_in;
  cudaMalloc(&d_p, 3 * sizeof(double) * n);
  cudaMalloc(&d_d, sizeof(double) * n);
  cudaMalloc(&d_g, 3 * sizeof(double) * n);
  cudaMalloc(&d_in, n);
  cudaMemcpy(d_p, xyz.data(), 3 * sizeof(double) * n, cudaMemcpyHostToDevice);
  for (int r = 0; r < 3; ++r) sampler.sample_device(d_p, n, d_d, d_g, d_in);  // warm-up
  std::vector<double> kq;
  for (int r = 0; r < 21; ++r) kq.push_back(sampler.sample_device(d_p, n, d_d, d_g, d_in));
  std::vector<double> d(n), g(3 * size_t(n));
  std::vector<uint8_t> in(n);
  std::vector<double> wall;
  for (int r = 0; r < 5; ++r) {
    auto t0 = Clock::now();
    sampler.sample(xyz.data(), n, d.data(), g.data(), in.data());
    wall.push_back(ms_since(t0));
  }
  double worst = 0;
  for (int i = 0; i < n; ++i) worst = std::max(worst, std::abs(d[i] - cpu_out[i].distance_m));
  const double k_ms = median(kq), c_ms = median(cpu_q), w_ms = median(wall);
  std::printf("\n| query (0.2 mm field, %d points) | ms | points/s |\n|---|---|---|\n", n);
  std::printf("| CPU sample(), 1 thread | %.1f | %.3g |\n", c_ms, n / (c_ms * 1e-3));
  std::printf("| GPU kernel (device arrays, CUDA events, median of 21) | %.3f | %.3g |\n", k_ms, n / (k_ms * 1e-3));
  std::printf("| GPU incl. host<->device copies (median of 5) | %.1f | %.3g |\n", w_ms, n / (w_ms * 1e-3));
  std::printf("\nmax |distance CPU - GPU| over the queries: %.3g m\n", worst);
  cudaFree(d_p), cudaFree(d_d), cudaFree(d_g), cudaFree(d_in);
  return 0;
}
