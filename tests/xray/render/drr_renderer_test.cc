#include "xray/render/drr_renderer.h"

#include <gtest/gtest.h>

#include "anatomy/phantom/thorax_phantom.h"
#include "xray/projectors/siddon_projector.h"

namespace pcisim::xray {
namespace {

TEST(DrrRenderer, RendersAPoseLikeTheProjectorItWraps) {
  anatomy::ThoraxPhantomSpec s;
  s.dims = {64, 64, 32};
  s.spacing_mm = 5.6;
  const anatomy::Volume v = anatomy::make_thorax_phantom(s);
  CArmSpec c;
  c.width = 24;
  c.height = 20;
  c.pixel_mm = 8;
  const CArmPose pose{-30, 15, Eigen::Vector3d(0, 0, 10)};  // RAO 30 CRA 15
  DrrRendererOptions exact_options, cpu_options;
  exact_options.projector = ProjectorKind::kExact;
  cpu_options.projector = ProjectorKind::kCpuTrilinear;
  cpu_options.trilinear.step_voxels = 0.25;
  DrrRenderer exact(v, exact_options);
  DrrRenderer cpu(v, cpu_options);
  Image a, b;  // sized by the renderer
  exact.render(c, pose, &a);
  cpu.render(c, pose, &b);
  ASSERT_EQ(a.width, 24);
  ASSERT_EQ(b.height, 20);
  const DetectorGeometry g = c_arm_geometry(c, pose);
  double peak = 0, sq = 0;
  for (int r = 0; r < 20; ++r) {
    for (int col = 0; col < 24; ++col) {
      const double want = exact_line_integral(exact.attenuation(), g.source_mm, g.pixel_center_mm(col, r));
      EXPECT_NEAR(a.at(col, r), want, 1e-5 * std::max(1.0, want));
      peak = std::max(peak, want);
      sq += (b.at(col, r) - want) * (b.at(col, r) - want);
    }
  }
  EXPECT_GT(peak, 1.0);
  // coarse 5.6 mm voxels: trilinear and nearest differ more than on the fine phantom (~0.1 %)
  EXPECT_LT(std::sqrt(sq / (24 * 20)) / peak, 0.02);
#ifndef PCISIM_HAVE_CUDA
  DrrRendererOptions cuda_options;
  cuda_options.projector = ProjectorKind::kCudaTrilinear;
  EXPECT_THROW(DrrRenderer(v, cuda_options), std::runtime_error);
#endif
}

}  // namespace
}  // namespace pcisim::xray
