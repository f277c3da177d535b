// Gap bridging on painted volumes with exact truth: a vessel cut by a gap is joined end to end; a
// blob, a vessel lying side by side with the region, and a gap wider than the limit are not.
#include "modeling/cta/gap_bridging.h"

#include <gtest/gtest.h>

#include <functional>

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

constexpr double kLumenHu = 300, kTissueHu = 40, kLower = 150, kUpper = 650;

// a 60 mm cube at 0.5 mm voxels, tissue everywhere, lumen where `inside` says
anatomy::Volume paint(const std::function<bool(const Vector3d&)>& inside) {
  anatomy::Volume v =
      anatomy::Volume::make({120, 120, 120}, Vector3d::Constant(0.5), Vector3d::Zero(), anatomy::VoxelType::kInt16);
  for (int64_t k = 0; k < 120; ++k)
    for (int64_t j = 0; j < 120; ++j)
      for (int64_t i = 0; i < 120; ++i)
        v.hu_i16[v.linear_index(i, j, k)] = inside(v.index_to_physical_mm(Vector3d(i, j, k))) ? kLumenHu : kTissueHu;
  return v;
}

// within r of the segment a-b
bool in_tube(const Vector3d& p, const Vector3d& a, const Vector3d& b, double r) {
  const Vector3d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - p).norm() <= r;
}

// the region: the voxels of the first tube (as the region grown from a seed would be)
Mask region_of(const anatomy::Volume& v, const Vector3d& a, const Vector3d& b, double r) {
  Mask m = Mask::zeros(ImageGrid::of(v));
  for (int64_t n = 0; n < m.grid.size(); ++n) {
    const auto [i, j, k] = m.grid.ijk(n);
    m.v[n] = in_tube(v.index_to_physical_mm(Vector3d(i, j, k)), a, b, r) ? 1 : 0;
  }
  return m;
}

TEST(GapBridging, AVesselCutByAGapIsJoinedEndToEnd) {
  // along x: capsules of radius 1.5 mm around 5..25 mm and 32..55 mm: lumen to 26.5 mm, a 4 mm
  // gap, lumen from 30.5 mm
  const Vector3d a(5, 30, 30), b(25, 30, 30), c(32, 30, 30), d(55, 30, 30);
  const anatomy::Volume v = paint([&](const Vector3d& p) { return in_tube(p, a, b, 1.5) || in_tube(p, c, d, 1.5); });
  Mask region = region_of(v, a, b, 1.5);
  const int64_t before = region.count();
  const std::vector<Bridge> bridges = bridge_gaps(v, kLower, kUpper, &region, GapBridgingOptions{});
  ASSERT_EQ(bridges.size(), 1u);
  EXPECT_NEAR(bridges[0].from_mm.x(), 26.5, 0.6);
  EXPECT_NEAR(bridges[0].to_mm.x(), 30.5, 0.6);
  EXPECT_NEAR(bridges[0].gap_mm, 4.0, 1.0);
  EXPECT_NEAR(bridges[0].piece_length_mm, 23.0 + 3.0, 1.0);  // the piece's extent, its round ends included
  // the far vessel is now in the region, and the gap's middle
  const ImageGrid g = region.grid;
  auto at = [&](const Vector3d& p_mm) {
    const Vector3d c = g.continuous_index(p_mm);
    return region.v[g.index(std::llround(c.x()), std::llround(c.y()), std::llround(c.z()))];
  };
  EXPECT_EQ(at(Vector3d(45, 30, 30)), 1);
  EXPECT_EQ(at(Vector3d(28.5, 30, 30)), 1);
  EXPECT_GT(region.count(), before);
  // nothing else marked: every region voxel is in a tube or on the line across the gap
  for (int64_t n = 0; n < g.size(); ++n) {
    if (!region.v[n]) continue;
    const auto [i, j, k] = g.ijk(n);
    const Vector3d p = g.physical_mm(Vector3d(i, j, k));
    ASSERT_TRUE(in_tube(p, a, d, 1.6)) << p.transpose();
  }
}

TEST(GapBridging, AChamberNearAVesselEndIsNotJoined) {
  // the vessel ends 5 mm from a ball of radius 10 mm (a chamber), pointing at it
  const Vector3d a(5, 30, 30), b(20, 30, 30), centre(35, 30, 30);
  const anatomy::Volume v =
      paint([&](const Vector3d& p) { return in_tube(p, a, b, 1.5) || (p - centre).norm() <= 10.0; });
  Mask region = region_of(v, a, b, 1.5);
  const int64_t before = region.count();
  EXPECT_TRUE(bridge_gaps(v, kLower, kUpper, &region, GapBridgingOptions{}).empty());
  EXPECT_EQ(region.count(), before);
}

TEST(GapBridging, BoneMarrowOrNoiseAheadOfAVesselEndIsNotJoined) {
  const Vector3d a(5, 30, 30), b(25, 30, 30), c(32, 30, 30), d(55, 30, 30);
  // a rib ahead: marrow of lumen HU inside a cortex brighter than lumen
  {
    anatomy::Volume v = paint([&](const Vector3d& p) { return in_tube(p, a, b, 1.5) || in_tube(p, c, d, 2.0); });
    for (int64_t n = 0; n < v.voxel_count(); ++n) {
      const auto p = v.index_to_physical_mm(Vector3d(n % 120, (n / 120) % 120, n / 14400));
      if (!in_tube(p, c, d, 2.0) && in_tube(p, c, d, 3.0) && !in_tube(p, a, b, 1.5)) v.hu_i16[n] = 900;
    }
    Mask region = region_of(v, a, b, 1.5);
    EXPECT_TRUE(bridge_gaps(v, kLower, kUpper, &region, GapBridgingOptions{}).empty()) << "rib";
  }
  // noise ahead: one voxel in five of a 3 mm tube above the threshold, strung through corners
  {
    uint32_t state = 12345;
    auto coin = [&] {
      state = state * 1664525u + 1013904223u;
      return (state >> 8) % 5 == 0;
    };
    const anatomy::Volume v =
        paint([&](const Vector3d& p) { return in_tube(p, a, b, 1.5) || (in_tube(p, c, d, 3.0) && coin()); });
    Mask region = region_of(v, a, b, 1.5);
    EXPECT_TRUE(bridge_gaps(v, kLower, kUpper, &region, GapBridgingOptions{}).empty()) << "noise";
  }
}

TEST(GapBridging, APieceMuchBrighterThanTheVesselEndIsNotJoined) {
  // the blurred rim of a rib falls under the upper threshold as a sheath far brighter than a distal
  // vessel: here the piece ahead at 600 HU against the vessel's 300 (a vessel does not brighten
  // distally); with the contrast window widened to a factor 0.4 the same piece is joined
  const Vector3d a(5, 30, 30), b(25, 30, 30), c(32, 30, 30), d(55, 30, 30);
  anatomy::Volume v = paint([&](const Vector3d& p) { return in_tube(p, a, b, 1.5) || in_tube(p, c, d, 1.5); });
  for (int64_t n = 0; n < v.voxel_count(); ++n) {
    const auto p = v.index_to_physical_mm(Vector3d(n % 120, (n / 120) % 120, n / 14400));
    if (in_tube(p, c, d, 1.5)) v.hu_i16[n] = 600;
  }
  Mask region = region_of(v, a, b, 1.5);
  EXPECT_TRUE(bridge_gaps(v, kLower, kUpper, &region, GapBridgingOptions{}).empty());
  GapBridgingOptions wide;
  wide.min_contrast_ratio = 0.4;
  EXPECT_EQ(bridge_gaps(v, kLower, kUpper, &region, wide).size(), 1u);
}

TEST(GapBridging, AVesselBesideTheRegionOrTooFarIsNotJoined) {
  // side by side: a parallel vessel 4 mm to the side of the region's vessel (a vein along an artery)
  {
    const Vector3d a(5, 30, 30), b(50, 30, 30), c(5, 34, 30), d(50, 34, 30);
    const anatomy::Volume v = paint([&](const Vector3d& p) { return in_tube(p, a, b, 1.5) || in_tube(p, c, d, 1.2); });
    Mask region = region_of(v, a, b, 1.5);
    EXPECT_TRUE(bridge_gaps(v, kLower, kUpper, &region, GapBridgingOptions{}).empty());
  }
  // end to end, but 14 mm apart: over the 10 mm limit
  {
    const Vector3d a(5, 30, 30), b(20, 30, 30), c(34, 30, 30), d(55, 30, 30);
    const anatomy::Volume v = paint([&](const Vector3d& p) { return in_tube(p, a, b, 1.5) || in_tube(p, c, d, 1.5); });
    Mask region = region_of(v, a, b, 1.5);
    EXPECT_TRUE(bridge_gaps(v, kLower, kUpper, &region, GapBridgingOptions{}).empty());
  }
  // off: nothing
  {
    const Vector3d a(5, 30, 30), b(25, 30, 30), c(29, 30, 30), d(55, 30, 30);
    const anatomy::Volume v = paint([&](const Vector3d& p) { return in_tube(p, a, b, 1.5) || in_tube(p, c, d, 1.5); });
    Mask region = region_of(v, a, b, 1.5);
    GapBridgingOptions off;
    off.enabled = false;
    EXPECT_TRUE(bridge_gaps(v, kLower, kUpper, &region, off).empty());
  }
}

}  // namespace
}  // namespace pcisim::modeling
