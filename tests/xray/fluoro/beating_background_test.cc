#include "xray/fluoro/beating_background.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
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

// a background over another's changes (a dataset's jobs share them) gives the same frames bit for
// bit and holds the very same volumes; changes of another beat's box are refused
TEST(BeatingBackground, SharedChangesGiveTheSameFramesAndChangesOfAnotherBoxAreRefused) {
  const AttenuationVolume mu(ct(Eigen::Vector3d::Zero()));
  const DetectorGeometry g = ap();
  const Image still = still_projection(mu, g, 1.0);
  const BeatingBackgroundOptions options{.projector = {.step_voxels = 1.0, .threads = 1}};
  BeatingBackground first(mu, rigid_beat(4), options);
  ASSERT_NE(first.changes(), nullptr);
  BeatingBackground second(mu, rigid_beat(4), options, first.changes());
  EXPECT_EQ(second.changes(), first.changes()) << "shared, not copied";
  first.set_pose(g, still);
  second.set_pose(g, still);
  Image a, b;
  for (const double phase : {0.0, 0.3, 0.61}) {
    first.at_phase(phase, &a);
    second.at_phase(phase, &b);
    EXPECT_EQ(a.pixels, b.pixels) << "phase " << phase;
  }
  // more bins, or a heart whose samples reach elsewhere (another box), do not fit
  EXPECT_THROW(BeatingBackground(mu, rigid_beat(6), options, first.changes()), std::invalid_argument);
  BeatSamples wider = rigid_beat(4);
  for (auto& p : wider.rest_mm) p *= 1.5;
  for (auto& bin : wider.at_bin_mm)
    for (auto& p : bin) p *= 1.5;
  EXPECT_THROW(BeatingBackground(mu, wider, options, first.changes()), std::invalid_argument);
}

TEST(BeatingBackground, TheCoarseDetectorIsCentredForAnyWidth) {
  const AttenuationVolume mu(ct(Eigen::Vector3d::Zero()));
  for (const int width : {157, 161}) {
    CArmSpec spec;
    spec.width = width;
    spec.height = 150;
    spec.pixel_mm = 1.0;
    const DetectorGeometry g = c_arm_geometry(spec, CArmPose{0, 0, Eigen::Vector3d::Zero()});
    const Image still = still_projection(mu, g, 1.0);
    Image full, coarse;
    // changes written when projected: only bin 1's is needed
    BeatingBackground a(mu, rigid_beat(4),
                        {.change_stride = 1, .change_cache_mib = 0, .projector = {.step_voxels = 1.0, .threads = 1}});
    BeatingBackground b(mu, rigid_beat(4),
                        {.change_stride = 2, .change_cache_mib = 0, .projector = {.step_voxels = 1.0, .threads = 1}});
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
    // as in the even case (0.045 at 160 px)
    EXPECT_LT(std::sqrt(se / change), 0.07) << "width " << width;
  }
}

// the length inside the 20 mm ball centred at c of the ray from the source to detector point p,
// and how far the ray passes from c
double chord_mm(const DetectorGeometry& g, const Eigen::Vector3d& p, const Eigen::Vector3d& c) {
  const double d2 = (c - g.source_mm).cross((p - g.source_mm).normalized()).squaredNorm();
  return d2 < 400 ? 2 * std::sqrt(400 - d2) : 0.0;
}
double miss_mm(const DetectorGeometry& g, const Eigen::Vector3d& p, const Eigen::Vector3d& c) {
  return (c - g.source_mm).cross((p - g.source_mm).normalized()).norm();
}

// a detector of 11 x 7 pixels of 16 mm (the heart and the spine in a few rays each, coarse
// detectors of 6 x 4 and 3 x 2 pixels): each pixel against the straightforward path, the moved CT
// projected whole; the change coarse pixel by coarse pixel, each centred where the header says.
// A heart that does not move leaves every bin the still projection
TEST(BeatingBackground, OnASmallDetectorEachPixelIsTheMovedHeartsProjectionOrTheStillOne) {
  const AttenuationVolume mu(ct(Eigen::Vector3d::Zero()));
  CArmSpec spec;
  spec.width = 11;
  spec.height = 7;
  spec.pixel_mm = 16.0;
  const DetectorGeometry g = c_arm_geometry(spec, CArmPose{0, 0, Eigen::Vector3d::Zero()});
  const Image still = still_projection(mu, g, 1.0);
  const AttenuationVolume moved_mu(ct(shift_mm(0.25)));
  const double water = mu.mu_of_hu(40);  // air is 0
  for (const int stride : {1, 2, 4}) {
    // changes written when projected (only bin 1 is needed here)
    BeatingBackground beat(
        mu, rigid_beat(4),
        {.change_stride = stride, .change_cache_mib = 0, .projector = {.step_voxels = 1.0, .threads = 1}});
    beat.set_pose(g, still);
    Image got;
    beat.at_phase(0.25, &got);
    ASSERT_EQ(got.width, 11);
    ASSERT_EQ(got.height, 7);
    // the coarse detector's truth: coarse pixel (C, R) is centred on fine pixel
    // (s C + (s - 1) / 2, s R + (s - 1) / 2); the moved CT's projection there less the still one,
    // then bilinear over the coarse pixels (clamped at the edges)
    DetectorGeometry gc = g;
    gc.width = (g.width + stride - 1) / stride;
    gc.height = (g.height + stride - 1) / stride;
    gc.pixel_mm = g.pixel_mm * stride;
    gc.center_mm = g.pixel_center_mm(stride * 0.5 * (gc.width - 1) + 0.5 * (stride - 1),
                                     stride * 0.5 * (gc.height - 1) + 0.5 * (stride - 1));
    const Image coarse_moved = still_projection(moved_mu, gc, 1.0), coarse_still = still_projection(mu, gc, 1.0);
    auto coarse_change = [&](int c, int r) { return double(coarse_moved.at(c, r)) - coarse_still.at(c, r); };
    double worst = 0;
    for (int r = 0; r < g.height; ++r)
      for (int c = 0; c < g.width; ++c) {
        const double x = std::clamp((c - 0.5 * (stride - 1)) / stride, 0.0, gc.width - 1.0);
        const double y = std::clamp((r - 0.5 * (stride - 1)) / stride, 0.0, gc.height - 1.0);
        const int x0 = std::min(static_cast<int>(x), std::max(gc.width - 2, 0)), x1 = std::min(x0 + 1, gc.width - 1);
        const int y0 = std::min(static_cast<int>(y), std::max(gc.height - 2, 0)), y1 = std::min(y0 + 1, gc.height - 1);
        const double fx = x - x0, fy = y - y0;
        const double change = (1 - fy) * ((1 - fx) * coarse_change(x0, y0) + fx * coarse_change(x1, y0)) +
                              fy * ((1 - fx) * coarse_change(x0, y1) + fx * coarse_change(x1, y1));
        worst = std::max(worst, std::abs(got.at(c, r) - (still.at(c, r) + change)));
      }
    // measured 7e-7 (stride 1), 1.1e-6 (2), 5.5e-7 (4) of line integrals up to 1.36: float
    // sums in another order; bound 3e-6. Coarse pixels half a fine pixel off centre: 0.16 (2), 0.14 (4)
    EXPECT_LT(worst, 3e-6) << "stride " << stride;
    if (stride == 1) {
      // where the heart moved the image moved, by the ball's chords: the 8 rays whose chord
      // through it changes by more than 6 mm (+-6.6 to 25.5 mm) see that much more or less water
      // within 2.3 mm (the ball is of 2 mm voxels; bound 3.5 mm), the mirrored motion would be
      // 13 mm or more off; the 56 rays that miss the ball at rest and moved by 25 mm (the spine's
      // among them) do not change at all
      int changed = 0, still_pixels = 0;
      for (int r = 0; r < g.height; ++r)
        for (int c = 0; c < g.width; ++c) {
          const Eigen::Vector3d p = g.pixel_center_mm(c, r);
          const double dl_mm = chord_mm(g, p, shift_mm(0.25)) - chord_mm(g, p, Eigen::Vector3d::Zero());
          const double d = got.at(c, r) - still.at(c, r);
          if (std::min(miss_mm(g, p, Eigen::Vector3d::Zero()), miss_mm(g, p, shift_mm(0.25))) > 25) {
            EXPECT_EQ(got.at(c, r), still.at(c, r)) << c << "," << r;
            ++still_pixels;
          } else if (std::abs(dl_mm) > 6) {
            EXPECT_NEAR(d / water, dl_mm, 3.5) << c << "," << r;
            ++changed;
          }
        }
      EXPECT_EQ(changed, 8);
      EXPECT_EQ(still_pixels, 56);
    }
  }
  // a heart that does not move: every bin is the still projection, bit for bit
  BeatSamples rest = rigid_beat(2);
  for (auto& bin : rest.at_bin_mm) bin = rest.rest_mm;
  BeatingBackground beat(mu, rest, {.change_cache_mib = 0, .projector = {.step_voxels = 1.0, .threads = 1}});
  beat.set_pose(g, still);
  Image got;
  for (const double phase : {0.0, 0.5, 0.1, 0.3, 0.37, 0.61, 0.85, 0.97}) {  // the bins and blends of them
    beat.at_phase(phase, &got);
    EXPECT_EQ(got.pixels, still.pixels) << "phase " << phase;
  }
  EXPECT_EQ(beat.filled_bins(), 2);
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

float largest(const Image& im) {
  float top = 0;
  for (const float p : im.pixels) top = std::max(top, std::abs(p));
  return top;
}
float worst_difference(const Image& a, const Image& b) {
  float worst = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) worst = std::max(worst, std::abs(a.pixels[i] - b.pixels[i]));
  return worst;
}

// a stand-in for a quick static projection: the whole one, a little off
Image quick_projection_of(const Image& whole) {
  Image quick = whole;
  for (size_t i = 0; i < quick.pixels.size(); ++i) quick.pixels[i] *= 0.9f + 0.0001f * (i % 7);
  return quick;
}

TEST(BeatingBackground, ANewStaticProjectionOfThePoseReplacesTheOldInEveryBin) {
  // a C-arm move's quick static projection refined: each bin, filled or not, is what setting the
  // pose with the refined projection would have given (its change is not projected again)
  const AttenuationVolume mu(ct(Eigen::Vector3d::Zero()));
  const DetectorGeometry g = ap();
  const Image whole = still_projection(mu, g, 1.0);
  const Image quick = quick_projection_of(whole);
  const BeatingBackgroundOptions o{.interpolate = false, .projector = {.step_voxels = 1.0, .threads = 1}};
  BeatingBackground refined(mu, rigid_beat(4), o), direct(mu, rigid_beat(4), o);
  refined.set_pose(g, quick);
  direct.set_pose(g, whole);
  Image a, b;
  refined.at_phase(0.0, &a);  // bin 0 filled on the quick projection, the others not yet
  const int64_t projected = refined.bin_projections();
  refined.replace_static(quick, whole);
  EXPECT_EQ(refined.bin_projections(), projected) << "no change projected again";
  for (const double phase : {0.0, 0.25, 0.5}) {
    refined.at_phase(phase, &a);
    direct.at_phase(phase, &b);
    EXPECT_LT(worst_difference(a, b), 1e-5f * largest(b)) << "phase " << phase;
  }
  Image wrong;
  wrong.resize(3, 3);
  EXPECT_THROW(refined.replace_static(wrong, wrong), std::invalid_argument);

  // a quick pose (a C-arm move's first frame): the bins it fills before the whole projection
  // arrives have their change on the coarser detector, and are projected again afterwards
  BeatingBackground moved(mu, rigid_beat(4), o);
  moved.set_pose(g, quick_projection_of(whole), 4);
  moved.at_phase(0.25, &a);
  EXPECT_EQ(moved.filled_bins(), 0) << "bin 1 filled quickly";
  EXPECT_EQ(moved.fill_ahead(), 1) << "bin 0, quickly too";
  EXPECT_EQ(moved.filled_bins(), 0);
  moved.replace_static(quick_projection_of(whole), whole);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(moved.fill_ahead(), 1) << k;  // bins 2, 3, then 0 and 1 again
  EXPECT_EQ(moved.fill_ahead(), 0);
  EXPECT_EQ(moved.filled_bins(), 4);
  for (const double phase : {0.0, 0.25, 0.5}) {
    moved.at_phase(phase, &a);
    direct.at_phase(phase, &b);
    EXPECT_LT(worst_difference(a, b), 1e-5f * largest(b)) << "phase " << phase << ", after the quick pose";
  }
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
