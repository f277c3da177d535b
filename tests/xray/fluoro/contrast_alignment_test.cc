// The analytic iodine lands where the CT phantom paints the lumens: the overlay of every lumen
// segment at full opacity against the DRR difference of the phantom with iodine-filled and with
// blood-filled lumens (same tree, same frame).
#include <gtest/gtest.h>

#include <cmath>

#include "anatomy/phantom/coronary_phantom.h"
#include "xray/fluoro/contrast_bolus.h"
#include "xray/geometry/c_arm.h"
#include "xray/overlay/tube_overlay.h"
#include "anatomy/phantom/thorax_phantom.h"
#include "xray/render/drr_renderer.h"

namespace pcisim::xray {
namespace {

double correlation(const Image& a, const Image& b, int dc, int dr) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  int n = 0;
  for (int r = 8; r < a.height - 8; ++r) {
    for (int c = 8; c < a.width - 8; ++c) {
      const double x = a.at(c, r), y = b.at(c + dc, r + dr);
      sa += x, sb += y, saa += x * x, sbb += y * y, sab += x * y;
      ++n;
    }
  }
  const double cov = sab / n - sa / n * sb / n;
  return cov / std::sqrt((saa / n - sa / n * sa / n) * (sbb / n - sb / n * sb / n));
}

TEST(ContrastAlignment, AnalyticIodineMatchesTheCtLumens) {
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({.seed = 1});
  const double mu_water = 0.02, iodine_mu = 0.05;  // +2500 HU: fits the phantom's int16 range
  anatomy::ThoraxPhantomSpec ps;
  ps.dims = {120, 120, 120};
  ps.spacing_mm = 1.0;
  ps.center_mm = Eigen::Vector3d::Zero();  // the heart only
  ps.threads = 1;
  ps.contrast = false;
  DrrRendererOptions o;
  o.trilinear.threads = 1;
  o.attenuation.mu_water_per_mm = mu_water;
  DrrRenderer blood(anatomy::make_thorax_phantom(ps, tree), o);
  ps.contrast = true;
  ps.contrast_hu = ps.hu.blood + 1000.0 * iodine_mu / mu_water;
  DrrRenderer iodine(anatomy::make_thorax_phantom(ps, tree), o);

  CArmSpec c;
  c.width = c.height = 128;
  c.pixel_mm = 1.2;
  const DetectorGeometry g = c_arm_geometry(c, CArmPose{30, 20, Eigen::Vector3d::Zero()});
  Image a, b, voxelised, analytic;
  blood.render(g, &a);
  iodine.render(g, &b);
  voxelised.resize(g.width, g.height);
  for (size_t i = 0; i < a.pixels.size(); ++i) voxelised.pixels[i] = b.pixels[i] - a.pixels[i];
  analytic.resize(g.width, g.height);
  const ContrastBolus bolus(tree, ContrastBolusSpec{});
  for (const LumenSegment& s : bolus.segments()) {
    add_cone_segment(g, s.a_mm, s.b_mm, s.ra_mm, s.rb_mm, iodine_mu, &analytic);
  }
  double sum_v = 0, sum_a = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    sum_v += voxelised.pixels[i];
    sum_a += analytic.pixels[i];
  }
  ASSERT_GT(sum_v, 0);
  // the same iodine volume (lumen volume x mu, magnified): within the voxelisation's error
  EXPECT_NEAR(sum_a / sum_v, 1.0, 0.05);
  const double c0 = correlation(voxelised, analytic, 0, 0);
  EXPECT_GT(c0, 0.93);  // 0.965 when written
  // and in the same place: any shift of 2 px (~1.6 mm at the heart) matches worse
  for (const auto& [dc, dr] : {std::pair{2, 0}, {-2, 0}, {0, 2}, {0, -2}}) {
    EXPECT_LT(correlation(voxelised, analytic, dc, dr), c0 - 0.2) << dc << ", " << dr;
  }
}

}  // namespace
}  // namespace pcisim::xray
