#include "xray/fluoro/beating_background.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "xray/geometry/c_arm.h"
#include "xray/projectors/trilinear_projector.h"

namespace pcisim::xray {
namespace {

// a 64^3 CT at 2 mm around the origin: air, a water ball of 20 mm radius (the heart) centred at
// `heart_mm`, and a bone block (the spine) at x in [48, 60] mm, far from the heart
anatomy::Volume ct(const Eigen::Vector3d& heart_mm) {
  anatomy::Volume v = anatomy::Volume::make({64, 64, 64}, Eigen::Vector3d::Constant(2.0),
                                            Eigen::Vector3d::Constant(-63.0), anatomy::VoxelType::kFloat32);
  for (int k = 0; k < 64; ++k)
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i) {
        const Eigen::Vector3d p = v.index_to_physical_mm(Eigen::Vector3d(i, j, k));
        float hu = -1000;
        if ((p - heart_mm).norm() <= 20) hu = 40;
        if (p.x() >= 48 && p.x() <= 60 && std::abs(p.z()) <= 30 && std::abs(p.y()) <= 20) hu = 700;
        v.hu_f32[v.linear_index(i, j, k)] = hu;
      }
  return v;
}

// the heart moves rigidly along x by 6 mm sin(2 pi phase): whole voxels at the quarter phases.
// Samples fill a ball of 26 mm around it every 4 mm.
Eigen::Vector3d shift_mm(double phase) {
  return Eigen::Vector3d(6.0 * std::sin(2 * std::numbers::pi * phase), 0, 0);
}

BeatSamples rigid_beat(int bins) {
  BeatSamples s;
  for (double x = -26; x <= 26; x += 4)
    for (double y = -26; y <= 26; y += 4)
      for (double z = -26; z <= 26; z += 4)
        if (Eigen::Vector3d(x, y, z).norm() <= 26) s.rest_mm.emplace_back(x, y, z);
  for (int b = 0; b < bins; ++b) {
    s.at_bin_mm.emplace_back();
    for (const auto& p : s.rest_mm) s.at_bin_mm.back().push_back(p + shift_mm(double(b) / bins));
  }
  return s;
}

DetectorGeometry ap() {
  CArmSpec spec;
  spec.width = spec.height = 160;
  spec.pixel_mm = 1.0;
  return c_arm_geometry(spec, CArmPose{0, 0, Eigen::Vector3d::Zero()});
}

// the still CT's projection for g, trilinear at `step` voxels, one thread
Image still_projection(const AttenuationVolume& mu, const DetectorGeometry& g, double step) {
  TrilinearProjector projector(mu, {.step_voxels = step, .threads = 1});
  Image still;
  still.resize(g.width, g.height);
  projector.project(g, &still);
  return still;
}

TEST(HeartWarp, MovesTheHeartAndLeavesWhatIsFarStill) {
  const AttenuationVolume mu(ct(Eigen::Vector3d::Zero()));
  const HeartWarp warp(mu, rigid_beat(4));
  // bin 1 is phase 0.25: +6 mm inside the heart, nothing at the spine
  EXPECT_NEAR((warp.displacement_mm(1, Eigen::Vector3d(5, -3, 8)) - shift_mm(0.25)).norm(), 0.0, 1e-4);
  EXPECT_NEAR((warp.displacement_mm(3, Eigen::Vector3d(0, 10, 0)) - shift_mm(0.75)).norm(), 0.0, 1e-4);
  EXPECT_EQ(warp.displacement_mm(1, Eigen::Vector3d(54, 0, 0)), Eigen::Vector3d::Zero());
  // the box stops short of the spine (x >= 48 mm is index >= 55.5)
  EXPECT_LT(warp.box_hi()[0], 55);
  // the change at bin 1 is the ball moved by three voxels, exactly (whole-voxel shift)
  AttenuationVolume change = warp.make_change_volume();
  warp.write_change(1, &change);
  const AttenuationVolume moved(ct(shift_mm(0.25)));
  double worst = 0;
  for (int k = warp.box_lo()[2]; k < warp.box_hi()[2]; ++k)
    for (int j = warp.box_lo()[1]; j < warp.box_hi()[1]; ++j)
      for (int i = warp.box_lo()[0]; i < warp.box_hi()[0]; ++i) {
        const float got = mu.mu(i, j, k) + change.mu(i - warp.box_lo()[0], j - warp.box_lo()[1], k - warp.box_lo()[2]);
        worst = std::max(worst, double(std::abs(got - moved.mu(i, j, k))));
      }
  EXPECT_LT(worst, 1e-4 * mu.mu_of_hu(40));
  // the whole warped CT (what per-frame re-projection projects): the moved ball everywhere
  AttenuationVolume whole(ct(Eigen::Vector3d::Zero()));
  warp.write_warped(1, &whole);
  double worst_whole = 0;
  for (int k = 0; k < 64; ++k)
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i)
        worst_whole = std::max(worst_whole, double(std::abs(whole.mu(i, j, k) - moved.mu(i, j, k))));
  EXPECT_LT(worst_whole, 1e-4 * mu.mu_of_hu(40));
}

TEST(BeatingBackground, MatchesProjectingTheMovedHeartAndTheSpineStaysBitIdentical) {
  const AttenuationVolume mu(ct(Eigen::Vector3d::Zero()));
  const DetectorGeometry g = ap();
  const Image still = still_projection(mu, g, 0.5);
  BeatingBackground beat(mu, rigid_beat(4), {.projector = {.step_voxels = 0.5, .threads = 1}});
  beat.set_pose(g, still);
  float top = 0;
  for (const float p : still.pixels) top = std::max(top, p);

  // every quarter phase against the exact truth: the CT with the heart moved, projected whole
  for (int b = 0; b < 4; ++b) {
    Image got;
    beat.at_phase(b / 4.0, &got);
    const Image truth = still_projection(AttenuationVolume(ct(shift_mm(b / 4.0))), g, 0.5);
    double se = 0;
    for (size_t i = 0; i < got.pixels.size(); ++i) se += std::pow(got.pixels[i] - truth.pixels[i], 2);
    EXPECT_LT(std::sqrt(se / got.pixels.size()), 0.005 * top) << "phase " << b / 4.0;
  }
  // the heart's edge (x = 20 mm, about column 80 + 20 x 1.47) changes between the phases, the
  // spine's pixels (x in [48, 60] mm) do not change at all
  Image a, c;
  beat.at_phase(0.25, &a);
  beat.at_phase(0.75, &c);
  const int row = g.height / 2;
  double heart_change = 0;
  for (int col = 100; col < 120; ++col)
    heart_change = std::max(heart_change, double(std::abs(a.at(col, row) - c.at(col, row))));
  EXPECT_GT(heart_change, 0.1 * top);
  int spine_pixels = 0;
  for (int r = 0; r < g.height; ++r)
    for (int col = 0; col < g.width; ++col) {
      const Eigen::Vector3d p = g.pixel_center_mm(col, r);
      const double x_at_axis = p.x() * 750.0 / 1100.0;  // back to the isocentre's plane
      if (x_at_axis < 47) continue;
      ++spine_pixels;
      ASSERT_EQ(a.at(col, r), still.at(col, r)) << col << "," << r;
      ASSERT_EQ(c.at(col, r), still.at(col, r)) << col << "," << r;
    }
  EXPECT_GT(spine_pixels, 500);
  EXPECT_EQ(beat.bin_projections(), 4);  // each bin once per pose
}

TEST(BeatingBackground, ACoarserChangeDetectorStaysCloseToTheFullOne) {
  const AttenuationVolume mu(ct(Eigen::Vector3d::Zero()));
  const DetectorGeometry g = ap();
  const Image still = still_projection(mu, g, 1.0);
  float top = 0;
  for (const float p : still.pixels) top = std::max(top, p);
  Image full, coarse;
  for (const int stride : {1, 2, 4}) {
    BeatingBackground beat(mu, rigid_beat(4),
                           {.change_stride = stride, .projector = {.step_voxels = 1.0, .threads = 1}});
    beat.set_pose(g, still);
    beat.at_phase(0.25, stride == 1 ? &full : &coarse);
    if (stride == 1) continue;
    // the same image within a fraction of the change (the ball's edge moved 6 mm); a wrong
    // pixel centring (half a coarse pixel) gives several times more
    double se = 0, change = 0;
    for (size_t i = 0; i < full.pixels.size(); ++i) {
      se += std::pow(coarse.pixels[i] - full.pixels[i], 2);
      change += std::pow(full.pixels[i] - still.pixels[i], 2);
    }
    EXPECT_LT(std::sqrt(se / change), stride == 2 ? 0.07 : 0.19) << "stride " << stride;
    std::printf("change stride %d: RMS difference %.4f of the change's RMS\n", stride, std::sqrt(se / change));
  }
}

TEST(BeatingBackground, BetweenBinsTheSpineStaysBitIdenticalAndTheUncachedPathMatches) {
  const AttenuationVolume mu(ct(Eigen::Vector3d::Zero()));
  const DetectorGeometry g = ap();
  const Image still = still_projection(mu, g, 1.0);
  BeatingBackground cached(mu, rigid_beat(4), {.projector = {.step_voxels = 1.0, .threads = 1}});
  BeatingBackground uncached(mu, rigid_beat(4),
                             {.change_cache_mib = 0, .projector = {.step_voxels = 1.0, .threads = 1}});
  ASSERT_TRUE(cached.changes_cached());
  ASSERT_FALSE(uncached.changes_cached());
  cached.set_pose(g, still);
  uncached.set_pose(g, still);
  Image a, b;
  for (const double phase : {0.3, 0.61, 0.97}) {  // blends of two bins
    cached.at_phase(phase, &a);
    uncached.at_phase(phase, &b);
    EXPECT_EQ(a.pixels, b.pixels) << "phase " << phase;
    for (int r = 0; r < g.height; ++r)
      for (int col = 0; col < g.width; ++col)
        if (g.pixel_center_mm(col, r).x() * 750.0 / 1100.0 >= 47)
          ASSERT_EQ(a.at(col, r), still.at(col, r)) << "phase " << phase << " pixel " << col << "," << r;
  }
}

TEST(BeatingBackground, TheCoarseDetectorIsCentredForAnyWidth) {
  const AttenuationVolume mu(ct(Eigen::Vector3d::Zero()));
  for (const int width : {157, 161, 3}) {
    CArmSpec spec;
    spec.width = width;
    spec.height = width == 3 ? 5 : 150;
    spec.pixel_mm = width == 3 ? 20.0 : 1.0;
    const DetectorGeometry g = c_arm_geometry(spec, CArmPose{0, 0, Eigen::Vector3d::Zero()});
    const Image still = still_projection(mu, g, 1.0);
    Image full, coarse;
    BeatingBackground a(mu, rigid_beat(4), {.change_stride = 1, .projector = {.step_voxels = 1.0, .threads = 1}});
    BeatingBackground b(mu, rigid_beat(4), {.change_stride = 2, .projector = {.step_voxels = 1.0, .threads = 1}});
    a.set_pose(g, still);
    b.set_pose(g, still);
    a.at_phase(0.25, &full);
    b.at_phase(0.25, &coarse);
    double se = 0, change = 0;
    for (size_t i = 0; i < full.pixels.size(); ++i) {
      se += std::pow(coarse.pixels[i] - full.pixels[i], 2);
      change += std::pow(full.pixels[i] - still.pixels[i], 2);
    }
    ASSERT_GT(change, 0) << width;
    // as in the even case (0.045 at 160 px); the tiny detector only has to stay in bounds and finite
    if (width != 3) EXPECT_LT(std::sqrt(se / change), 0.07) << "width " << width;
    for (const float p : coarse.pixels) ASSERT_TRUE(std::isfinite(p));
  }
}

TEST(BeatingBackground, BlendsTheTwoBinsAroundThePhaseOrTakesTheNearer) {
  const AttenuationVolume mu(ct(Eigen::Vector3d::Zero()));
  const DetectorGeometry g = ap();
  const Image still = still_projection(mu, g, 1.0);
  BeatingBackground blend(mu, rigid_beat(4), {.projector = {.step_voxels = 1.0, .threads = 1}});
  BeatingBackground nearest(mu, rigid_beat(4), {.interpolate = false, .projector = {.step_voxels = 1.0, .threads = 1}});
  blend.set_pose(g, still);
  nearest.set_pose(g, still);
  Image b0, b1, mid, near_lo, near_hi;
  blend.at_phase(0.0, &b0);
  blend.at_phase(0.25, &b1);
  blend.at_phase(0.125 + 0.03, &mid);  // 62 % of the way from bin 0 to bin 1
  const double t = (0.155 - 0.0) * 4;
  for (size_t i = 0; i < mid.pixels.size(); i += 97)
    ASSERT_NEAR(mid.pixels[i], (1 - t) * b0.pixels[i] + t * b1.pixels[i], 1e-5);
  nearest.at_phase(0.12, &near_lo);
  nearest.at_phase(1.13, &near_hi);  // phases wrap
  EXPECT_EQ(near_lo.pixels, b0.pixels);
  EXPECT_EQ(near_hi.pixels, b1.pixels);
  // the bins a frame did not need are filled ahead, one per call, until the pose has all
  EXPECT_EQ(nearest.filled_bins(), 2);
  EXPECT_EQ(nearest.fill_ahead(), 1);
  EXPECT_EQ(nearest.fill_ahead(), 1);
  EXPECT_EQ(nearest.fill_ahead(), 0);
  EXPECT_EQ(nearest.filled_bins(), 4);
}

TEST(BeatingBackground, RefusesBadSamplesNamingWhatIsWrong) {
  const AttenuationVolume mu(ct(Eigen::Vector3d::Zero()));
  BeatSamples one_bin = rigid_beat(1);
  EXPECT_THROW(BeatingBackground(mu, one_bin, {}), std::invalid_argument);
  BeatSamples short_bin = rigid_beat(4);
  short_bin.at_bin_mm[2].pop_back();
  try {
    BeatingBackground bad(mu, short_bin, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bin 2"), std::string::npos) << e.what();
  }
  BeatSamples nan = rigid_beat(4);
  nan.at_bin_mm[1][0].x() = NAN;
  EXPECT_THROW(BeatingBackground(mu, nan, {}), std::invalid_argument);
  BeatSamples outside = rigid_beat(4);
  for (auto& p : outside.rest_mm) p.x() += 500;
  for (auto& bin : outside.at_bin_mm)
    for (auto& p : bin) p.x() += 500;
  EXPECT_THROW(BeatingBackground(mu, outside, {}), std::invalid_argument);
  BeatingBackgroundOptions o;
  o.warp.kernel_mm = 0;
  EXPECT_THROW(BeatingBackground(mu, rigid_beat(4), o), std::invalid_argument);
  EXPECT_THROW(every_kth_bin(rigid_beat(6), 4), std::invalid_argument);
  EXPECT_EQ(every_kth_bin(rigid_beat(8), 2).bins(), 4);
}

}  // namespace
}  // namespace pcisim::xray
