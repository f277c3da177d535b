// Stage (b), clipping, on masks drawn with exact geometry: where a coronary piece's ostium is put
// when it touches the large lumen in more than one place, and what it counts as a sponge at the
// aortic root (issue #30).
#include "modeling/cta/coronary_clipping.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "modeling/cta/modeling_error.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

// a lumen mask on a 0.5 mm grid of 100 x 80 x 80 mm, drawn by an inside test (mm), seeded in the
// aorta; the HU are those of a lumen where drawn, fat elsewhere
LumenSegmentation drawn(const std::function<bool(const Vector3d&)>& inside) {
  ImageGrid g;
  g.dims = {200, 160, 160};
  g.spacing_mm = Vector3d::Constant(0.5);
  LumenSegmentation seg;
  seg.mask = Mask::zeros(g);
  seg.hu = FloatImage{g, std::vector<float>(g.size(), -100.0f)};
  for (int64_t n = 0; n < g.size(); ++n) {
    const auto [i, j, k] = g.ijk(n);
    if (inside(g.physical_mm(Vector3d(double(i), double(j), double(k))))) {
      seg.mask.v[n] = 1;
      seg.hu.v[n] = 400.0f;
    }
  }
  seg.lower_hu = 150;
  seg.upper_hu = 650;
  return seg;
}

double to_segment(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return (a + t * (b - a) - p).norm();
}

const Vector3d kAorta(25, 40, 40);  // its axis runs along z; radius 12 mm
bool aorta(const Vector3d& p) {
  return Vector3d(p.x() - kAorta.x(), p.y() - kAorta.y(), 0).norm() < 12;
}

// a vessel (1.5 mm radius) leaves the aorta's side at (37, 40, 40) and runs 50 mm along +x; 30 mm
// out it passes an appendage-like chamber (an 8 mm ball) that it touches along its side. Its
// ostium is on the aorta, not on the chamber it runs beside (family phantom: the LCx beside the
// left atrial appendage was traced from the appendage, its LM drawn straight across the heart)
TEST(CoronaryClipping, AVesselTouchingAChamberKeepsItsOstiumOnTheAorta) {
  const Vector3d from(37, 40, 40), to(87, 40, 40), ball(67, 40, 49.6);
  const LumenSegmentation seg = drawn([&](const Vector3d& p) {
    return aorta(p) || to_segment(p, from - Vector3d(2, 0, 0), to) < 1.5 || (p - ball).norm() < 8.0;
  });
  const Clipping c = clip_to_coronaries(seg, {kAorta}, ClippingOptions{});
  ASSERT_EQ(c.pieces.size(), 1u);
  EXPECT_LT((c.pieces[0].ostium_mm - from).norm(), 2.5) << c.pieces[0].ostium_mm.transpose();
  EXPECT_EQ(c.root_sponges, 0);
}

// a sponge (a lattice of bars, as noise strings a chamber at the threshold) attached at the aortic
// root is counted; with throw_when_none false no tree is an empty result that says why
TEST(CoronaryClipping, ASpongeAtTheRootIsCountedAndNoTreeIsSaid) {
  const LumenSegmentation seg = drawn([&](const Vector3d& p) {
    if (aorta(p)) return true;
    if (p.x() < 37 || p.x() > 80 || std::abs(p.y() - 40) > 15 || std::abs(p.z() - 40) > 15) return false;
    // bars 2 mm across every 4 mm along each axis: thin everywhere, filling its box
    auto wall = [](double v) { return std::fmod(v, 4.0) < 2.0; };
    return wall(p.x()) + wall(p.y()) + wall(p.z()) >= 2;
  });
  ClippingOptions o;
  EXPECT_THROW(clip_to_coronaries(seg, {kAorta}, o), ModelingError);
  o.throw_when_none = false;
  const Clipping c = clip_to_coronaries(seg, {kAorta}, o);
  EXPECT_TRUE(c.pieces.empty());
  EXPECT_EQ(c.root_sponges, 1);
  EXPECT_NE(c.none_found.find("no coronary artery found"), std::string::npos) << c.none_found;
  EXPECT_NE(c.none_found.find("noisy contrast"), std::string::npos) << c.none_found;
}

}  // namespace
}  // namespace pcisim::modeling
