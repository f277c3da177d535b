// The OSMesa GL projector against its CPU twin (the trilinear marcher without empty-space
// skipping, same step) and against the exact projector.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tests/xray/projectors/projector_test_util.h"
#include "xray/projectors/siddon_projector.h"
#include "xray/projectors/trilinear_projector.h"
#ifdef PCISIM_HAVE_OSMESA
#include "xray/projectors/gl/gl_projector.h"
#endif

namespace pcisim::xray {
namespace {

#ifdef PCISIM_HAVE_OSMESA
struct Errors {
  double peak = 0, worst = 0, rmse = 0;
};

Errors compare(const Image& a, const Image& b) {
  Errors e;
  double sq = 0;
  for (size_t n = 0; n < a.pixels.size(); ++n) {
    e.peak = std::max(e.peak, double(a.pixels[n]));
    const double d = std::abs(double(a.pixels[n]) - double(b.pixels[n]));
    e.worst = std::max(e.worst, d);
    sq += d * d;
  }
  e.rmse = std::sqrt(sq / a.pixels.size());
  return e;
}
#endif

TEST(GlProjector, MatchesItsCpuTwinAndTheExactProjector) {
#ifndef PCISIM_HAVE_OSMESA
  GTEST_SKIP() << "built without OSMesa (PCISIM_WITH_OSMESA=OFF): no GL projector to compare";
#else
  std::string why;
  if (!gl_projector_available(&why)) GTEST_SKIP() << "GL projector not compared: " << why;
  std::mt19937 rng(47);
  for (int trial = 0; trial < 3; ++trial) {
    const anatomy::Volume v = testing::random_volume(rng, /*smooth=*/true);
    const AttenuationVolume a(v);
    const DetectorGeometry g = testing::random_geometry(rng, v, 48, 37);
    Image gl, cpu, exact;
    for (Image* i : {&gl, &cpu, &exact}) i->resize(g.width, g.height);
    GlProjector(a, 0.5).project(g, &gl);
    TrilinearProjector(a, {.step_voxels = 0.5, .skip_empty = false, .threads = 1}).project(g, &cpu);
    SiddonProjector(a, 1).project(g, &exact);
    // twins: the same samples; only the texture filter's and the sum's float rounding differ
    // (seen: 2.6e-7 of the peak on Mesa llvmpipe): every pixel within 1e-5 of the largest
    const Errors twin = compare(cpu, gl);
    ASSERT_GT(twin.peak, 0.0) << "the comparison needs a non-empty projection";
    EXPECT_LE(twin.worst, 1e-5 * twin.peak) << "trial " << trial;
    // against exact (nearest-voxel) on a smooth volume: RMSE within 1 % of the peak
    const Errors vs_exact = compare(exact, gl);
    EXPECT_LE(vs_exact.rmse, 1e-2 * vs_exact.peak) << "trial " << trial;
  }
#endif
}

TEST(GlProjector, WaterBoxGivesItsChordLength) {
#ifndef PCISIM_HAVE_OSMESA
  GTEST_SKIP() << "built without OSMesa (PCISIM_WITH_OSMESA=OFF)";
#else
  std::string why;
  if (!gl_projector_available(&why)) GTEST_SKIP() << why;
  // a 20 mm water cube (HU 0: mu = 0.02 / mm) seen straight on: the central ray crosses 20 mm
  anatomy::Volume v = anatomy::Volume::make({20, 20, 20}, Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(-9.5, -9.5, -9.5),
                                            anatomy::VoxelType::kFloat32);
  std::fill(v.hu_f32.begin(), v.hu_f32.end(), 0.0f);
  const AttenuationVolume a(v);
  DetectorGeometry g;
  g.source_mm = Eigen::Vector3d(0, 500, 0);
  g.center_mm = Eigen::Vector3d(0, -500, 0);
  g.u = Eigen::Vector3d::UnitX();
  g.v = -Eigen::Vector3d::UnitZ();
  g.width = g.height = 9;
  g.pixel_mm = 1.0;
  Image gl;
  gl.resize(g.width, g.height);
  GlProjector(a, 0.25).project(g, &gl);
  // trilinear blurs the faces by half a voxel each side: 20 mm within a voxel's worth
  EXPECT_NEAR(gl.at(4, 4), 0.02 * 20.0, 0.02 * 1.0);
#endif
}

}  // namespace
}  // namespace pcisim::xray
