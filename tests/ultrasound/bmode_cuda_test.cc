// The CUDA B-mode renderer against its CPU twin (issue #32 item 3): the same kernels
// (render/bmode_kernels.h) on the GPU draw the CPU's frame of the kidney, pressed through its
// tets; and the renderer refuses, naming why, what it cannot draw on the GPU. The twin test skips
// where no GPU is visible (scripts/gpu-check runs it on one).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "anatomy/organ/kidney_phantom.h"
#include "ultrasound/render/bmode_renderer.h"
#include "ultrasound/tools/pressed_kidney.h"

namespace pcisim::ultrasound {
namespace {

// the pressed kidney seen from its anterior face, along its long axis (pcisim-us-kidney's pose)
ProbePose anterior_pose(const anatomy::KidneyPhantom& kidney) {
  ProbePose pose;
  pose.origin_mm = Eigen::Vector3d(0.0, kidney.ct.origin_mm.y(), 0.0);
  pose.beam = Eigen::Vector3d::UnitY();
  pose.lateral = Eigen::Vector3d::UnitZ();
  return pose;
}

// the message of the std::runtime_error a renderer with these settings throws, or ""
std::string refusal(const anatomy::Volume& ct, const UsSettings& s, const anatomy::TissueMap* map) {
  try {
    BModeRenderer r(ct, s, map);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(BModeCuda, TheGpuDrawsTheCpusFrameOfThePressedKidney) {
#ifndef PCISIM_HAVE_CUDA
  GTEST_SKIP() << "this build has no CUDA";
#else
  if (cuda::device_count() == 0) GTEST_SKIP() << "no CUDA device visible: the twin runs in scripts/gpu-check";
  std::printf("GPU: %s\n", cuda::device_name().c_str());
  const anatomy::KidneyPhantom kidney = anatomy::make_kidney_phantom();
  const anatomy::TissueMap map{kidney.tissue, anatomy::kidney_tissue_names()};
  TetSnapshot mesh = tools::kidney_tets(kidney.spec, 11.0);
  tools::press(mesh, 6.0, kidney.spec.semi_axes_mm.y());
  for (ProbeGeometry g : {ProbeGeometry::kCurvilinear, ProbeGeometry::kLinear}) {
    UsSettings s;
    s.geometry = g;
    s.width_mm = 50.0;
    s.height_px = 512;
    s.frequency_mhz = g == ProbeGeometry::kCurvilinear ? 3.5 : 7.5;
    s.threads = 2;
    BModeRenderer cpu(kidney.ct, s, &map);
    s.renderer = UsRenderer::kCuda;
    BModeRenderer gpu(kidney.ct, s, &map);
    // twice: the second frame reads the tets' second refit (a device buffer kept between frames)
    for (uint64_t seed : {7u, 8u}) {
      const BModeImage a = cpu.render(anterior_pose(kidney), seed, &mesh);
      const BModeImage b = gpu.render(anterior_pose(kidney), seed, &mesh);
      ASSERT_EQ(a.pixels.size(), b.pixels.size());
      // the echo intensity: the same arithmetic (no fused multiply-adds on the GPU), so equal but
      // for the math library's last place in exp and log
      const std::vector<float>& ea = cpu.echo_intensity();
      const std::vector<float>& eb = gpu.echo_intensity();
      double worst = 0.0;
      size_t lit = 0;
      for (size_t k = 0; k < ea.size(); ++k) {
        if (ea[k] < 1e-12f) continue;  // below the display's floor (-120 dB)
        ++lit;
        worst = std::max(worst, std::abs(static_cast<double>(eb[k]) - ea[k]) / ea[k]);
      }
      size_t differ = 0;
      int most = 0;
      for (size_t k = 0; k < a.pixels.size(); ++k) {
        const int d = std::abs(static_cast<int>(a.pixels[k]) - static_cast<int>(b.pixels[k]));
        differ += d != 0;
        most = std::max(most, d);
      }
      std::printf(
          "%s seed %d: echo relative difference at most %.3g over %zu samples; %zu of %zu grey levels "
          "differ, by at most %d; GPU kernels %.3f ms\n",
          g == ProbeGeometry::kCurvilinear ? "curvilinear" : "linear", static_cast<int>(seed), worst, lit, differ,
          a.pixels.size(), most, gpu.last_gpu_kernel_ms());
      EXPECT_GT(lit, ea.size() / 2);
      EXPECT_LT(worst, 1e-4);
      EXPECT_LE(most, 1);
      EXPECT_LE(differ, a.pixels.size() / 1000);
      EXPECT_GT(gpu.last_gpu_kernel_ms(), 0.0f);
    }
  }
#endif
}

// the GPU samples tissues, not HU: a CT without a tissue map is refused whatever the machine (a
// build without CUDA refuses every cuda renderer, naming that)
TEST(BModeCuda, TheCudaRendererRefusesWhatItCannotDraw) {
  const anatomy::KidneyPhantom kidney = anatomy::make_kidney_phantom();
  UsSettings s;
  s.renderer = UsRenderer::kCuda;
#ifdef PCISIM_HAVE_CUDA
  EXPECT_EQ(refusal(kidney.ct, s, nullptr),
            "ultrasound: the cuda renderer needs the case's tissue map (it samples tissues, not HU)");
  const anatomy::TissueMap map{kidney.tissue, anatomy::kidney_tissue_names()};
  if (cuda::device_count() == 0)
    EXPECT_EQ(refusal(kidney.ct, s, &map), "ultrasound: the cuda renderer: no CUDA device is visible");
  else
    EXPECT_EQ(refusal(kidney.ct, s, &map), "");
#else
  EXPECT_EQ(refusal(kidney.ct, s, nullptr), "ultrasound: the cuda renderer: this build has no CUDA (PCISIM_CUDA)");
#endif
}

}  // namespace
}  // namespace pcisim::ultrasound
