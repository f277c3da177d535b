// CUDA twin vs CPU twin of the SDF build and of batched sampling.
// Tolerances: the twins run the same double arithmetic (sdf_kernels.h) and store floats, so grid
// values may differ only where the GPU's fused multiply-adds change the last bits: we allow
// 1e-6 m (1 um, 1/200 of a 0.2 mm cell) per grid value and 1e-9 m / 1e-6 per sample.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "physics/sdf/signed_distance_field.h"
#include "anatomy/phantom/coronary_phantom.h"
#include "anatomy/vessel/lumen_mesh.h"

#ifdef PCISIM_HAVE_CUDA
#include "physics/sdf/signed_distance_field_cuda.h"
#endif

namespace pcisim::physics {
namespace {

#ifdef PCISIM_HAVE_CUDA

void skip_without_gpu() {
  std::string why;
  if (!cuda_sdf_available(&why)) GTEST_SKIP() << "no GPU here (" << why << "): CUDA vs CPU comparison skipped";
}

TEST(SdfCudaTest, BuildMatchesTheCpuTwin) {
  skip_without_gpu();
  if (IsSkipped()) return;
  const anatomy::TriangleMesh lumen = anatomy::loft_lumen(anatomy::make_coronary_phantom({.seed = 2}), {});
  SdfBuildSpec spec;
  spec.spacing_m = 0.2e-3;
  const SignedDistanceField cpu = SignedDistanceField::build(lumen, spec);
  CudaSdfBuildTimings t;
  const SignedDistanceField gpu = build_sdf_cuda(lumen, spec, &t);
  ASSERT_EQ(cpu.dims(), gpu.dims());
  ASSERT_EQ(cpu.brick_table(), gpu.brick_table()) << "the plan is the same CPU code: bricks must agree";
  ASSERT_EQ(cpu.values_m().size(), gpu.values_m().size());
  double worst = 0.0;
  size_t worst_at = 0;
  for (size_t i = 0; i < cpu.values_m().size(); ++i) {
    const double d = std::abs(double(cpu.values_m()[i]) - double(gpu.values_m()[i]));
    if (d > worst) worst = d, worst_at = i;
  }
  EXPECT_LE(worst, 1e-6) << "at pool index " << worst_at << ": cpu " << cpu.values_m()[worst_at] << " gpu "
                         << gpu.values_m()[worst_at];
  RecordProperty("gpu_kernels_ms", std::to_string(t.kernels_ms));
}

TEST(SdfCudaTest, BatchedSamplesMatchTheCpuTwin) {
  skip_without_gpu();
  if (IsSkipped()) return;
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({});
  const SignedDistanceField field = SignedDistanceField::build(anatomy::loft_lumen(tree, {}), 0.2e-3, 1e-3);
  // points near every centerline, some far outside the grid, and non-finite ones
  std::mt19937 rng(3);
  std::normal_distribution<double> jitter(0.0, 1.5e-3);
  std::vector<Eigen::Vector3d> pts;
  for (const auto& b : tree.branches) {
    for (const auto& p : b.points) pts.push_back(p.position_m + Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng)));
  }
  pts.push_back(Eigen::Vector3d(1.0, -2.0, 3.0));
  pts.push_back(Eigen::Vector3d(NAN, 0, 0));
  pts.push_back(Eigen::Vector3d(0, INFINITY, 0));
  const int n = static_cast<int>(pts.size());
  std::vector<double> xyz(3 * n), d(n), g(3 * n);
  std::vector<uint8_t> inside(n);
  for (int i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) xyz[3 * i + a] = pts[i][a];
  CudaSdfSampler sampler(field);
  sampler.sample(xyz.data(), n, d.data(), g.data(), inside.data());
  for (int i = 0; i < n; ++i) {
    const SdfSample s = field.sample(pts[i]);
    ASSERT_NEAR(d[i], s.distance_m, 1e-9) << "point " << i;
    for (int a = 0; a < 3; ++a) ASSERT_NEAR(g[3 * i + a], s.gradient[a], 1e-6) << "point " << i;
    ASSERT_EQ(inside[i] != 0, s.inside_grid) << "point " << i;
  }
}

#else

TEST(SdfCudaTest, SkippedWithoutCuda) {
  GTEST_SKIP() << "built without CUDA (no nvcc found): the CUDA SDF twin is not compiled";
}

#endif

}  // namespace
}  // namespace pcisim::physics
