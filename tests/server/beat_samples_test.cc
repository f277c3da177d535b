// The beating background and the moving tree agree: the CT warp built from one sampled cycle
// carries each coronary centerline point where the vessel skin carries it (the iodine and the
// wire are drawn at the skin's points, so the lumen in the warped CT must be there too), and the
// frames of the default scene differ where the heart moved and not far from it.
#include "server/beat_samples.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "anatomy/phantom/coronary_phantom.h"
#include "server/scene/scene.h"
#include "xray/fluoro/case_background.h"
#include "xray/fluoro/fluoroscopy.h"
#include "realtime/percentile.h"

namespace pcisim::server {
namespace {

struct Fixture {
  Scene scene = default_scene();
  anatomy::VesselTree tree = anatomy::make_coronary_phantom({.seed = scene.world.anatomy.seed});
  physics::BeatCycle cycle;
  xray::BeatSamples samples;
  xray::FluoroSpec spec;
  Fixture() {
    scene.world.guidewire.reset();  // the heart and the tree only
    scene.world.vessel_contact.reset();
    scene.world.friction.reset();
    scene.world.blood_flow.reset();
    physics::World world(scene.world);
    cycle = world.sample_beat_cycle(8);
    samples = beat_samples_mm(cycle);
    spec = scene.xray->fluoro;
    spec.c_arm.width = spec.c_arm.height = 256;
    spec.c_arm.pixel_mm = 0.8;
    spec.photons_per_pixel = 0;
    spec.blur_sigma_px = 0;
  }
};

TEST(BeatingBackgroundInTheScene, TheWarpCarriesTheCenterlineWhereTheSkinDoes) {
  const Fixture f;
  ASSERT_GT(f.cycle.heart_points, 0);
  ASSERT_EQ(f.samples.bins(), 8);
  const anatomy::Volume ct = xray::thorax_background(f.tree, f.spec);
  const xray::AttenuationVolume mu(ct);
  const xray::HeartWarp warp(mu, f.samples);
  // centerline points that ride the heart (moved > 1 mm at some bin), every bin
  std::vector<double> miss_mm, motion_mm;
  for (size_t i = f.cycle.heart_points; i < f.samples.rest_mm.size(); ++i) {
    double moved = 0;
    for (int b = 0; b < 8; ++b) moved = std::max(moved, (f.samples.at_bin_mm[b][i] - f.samples.rest_mm[i]).norm());
    if (moved < 1.0) continue;
    for (int b = 0; b < 8; ++b) {
      const Eigen::Vector3d rest = f.samples.rest_mm[i];
      miss_mm.push_back((rest + warp.displacement_mm(b, rest) - f.samples.at_bin_mm[b][i]).norm());
      motion_mm.push_back((f.samples.at_bin_mm[b][i] - rest).norm());
    }
  }
  ASSERT_GT(miss_mm.size(), 1000u);
  std::printf("centerline motion p95 %.2f mm; warp miss median %.3f p95 %.3f max %.3f mm (%zu point-bins)\n",
              realtime::percentile(motion_mm, 0.95), realtime::percentile(miss_mm, 0.5),
              realtime::percentile(miss_mm, 0.95), realtime::percentile(miss_mm, 1.0), miss_mm.size());
  // the tree moves by several mm; the warp lands within a fraction of a lumen radius (>= 1 mm)
  EXPECT_GT(realtime::percentile(motion_mm, 0.95), 4.0);
  EXPECT_LT(realtime::percentile(miss_mm, 0.5), 0.3) << "median miss, mm";
  EXPECT_LT(realtime::percentile(miss_mm, 0.95), 0.8) << "p95 miss, mm";
}

TEST(BeatingBackgroundInTheScene, FramesAtFourPhasesDifferOverTheHeartAndNotAtTheSpine) {
  const Fixture f;
  xray::FluoroSpec spec = f.spec;
  spec.c_arm.pixel_mm = 1.6;  // a 410 mm field: the whole chest, past the heart's box
  xray::FluoroscopyRenderer fr(f.tree, spec);
  fr.set_beat(f.samples);
  const xray::CArmPose ap{0, 0, Eigen::Vector3d::Zero()};
  std::vector<xray::Image> frames;
  for (const double phase : {0.0, 0.125, 0.25, 0.5}) {
    xray::FluoroFrame out;
    xray::FluoroInput in{.time_s = 0, .pose = ap};
    in.heart_phase = phase;
    fr.render(in, out);
    frames.push_back(fr.line_integrals());
  }
  xray::FluoroFrame out;
  fr.render({.time_s = 0, .pose = ap}, out);  // no phase: the still background
  const xray::Image still = fr.line_integrals();
  // the heart's projection (about the detector's centre) changes visibly from end-diastole to
  // mid-systole
  const int w = still.width, h = still.height;
  double top = 0, heart_change = 0;
  for (const float p : still.pixels) top = std::max<double>(top, p);
  for (int r = h / 2 - 30; r < h / 2 + 30; ++r)
    for (int c = w / 2 - 40; c < w / 2 + 40; ++c)
      heart_change = std::max(heart_change, double(std::abs(frames[2].at(c, r) - frames[0].at(c, r))));
  EXPECT_GT(heart_change, 0.05);  // 5 % of the intensity there (the line integral is a log)
  // phase 0 (end-diastole, rest) is the still background within rounding
  double rest_change = 0;
  for (size_t i = 0; i < still.pixels.size(); ++i)
    rest_change = std::max(rest_change, double(std::abs(frames[0].pixels[i] - still.pixels[i])));
  EXPECT_LT(rest_change, 0.005 * top);
  // pixels whose ray misses the warp's box (the CT voxels the heart's motion may change) are
  // bit-identical at every phase: the spine, the ribs and the lungs away from the heart
  const anatomy::Volume ct = xray::thorax_background(f.tree, spec);
  const auto& warp = fr.beat()->warp();
  const Eigen::Vector3d box_lo = ct.index_to_physical_mm(
      Eigen::Vector3d(warp.box_lo()[0], warp.box_lo()[1], warp.box_lo()[2]) - Eigen::Vector3d::Constant(1));
  const Eigen::Vector3d box_hi =
      ct.index_to_physical_mm(Eigen::Vector3d(warp.box_hi()[0], warp.box_hi()[1], warp.box_hi()[2]));
  const xray::DetectorGeometry& g = out.geometry;
  int far = 0;
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const Eigen::Vector3d a = g.source_mm, d = g.pixel_center_mm(c, r) - g.source_mm;
      double t0 = 0, t1 = 1;
      for (int k = 0; k < 3; ++k) {
        double ta = (box_lo[k] - a[k]) / d[k], tb = (box_hi[k] - a[k]) / d[k];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      if (t0 <= t1) continue;  // through the box
      ++far;
      for (const auto& img : frames) ASSERT_EQ(img.at(c, r), still.at(c, r)) << c << "," << r;
    }
  std::printf("heart change %.3f, rest change %.2e (largest line integral %.2f); %d of %d pixels miss the box\n",
              heart_change, rest_change, top, far, w * h);
  EXPECT_GT(far, 1000);
}

}  // namespace
}  // namespace pcisim::server
