#include "xray/fluoro/fluoroscopy.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "tests/xray/fluoro/fluoro_test_util.h"
#include "xray/overlay/wire_overlay.h"

namespace pcisim::xray {
namespace {

using testing::lao30_cra20;
using testing::small_fluoro_spec;

const anatomy::VesselTree& tree() {
  static const anatomy::VesselTree t = anatomy::make_coronary_phantom({.seed = 1});
  return t;
}

FluoroSpec noiseless() {
  FluoroSpec s = small_fluoro_spec();
  s.photons_per_pixel = 0;
  s.blur_sigma_px = 0;
  return s;
}

float bilinear(const Image& im, const Eigen::Vector2d& cr) {
  const int c = static_cast<int>(std::lround(cr.x())), r = static_cast<int>(std::lround(cr.y()));
  return im.at(std::clamp(c, 0, im.width - 1), std::clamp(r, 0, im.height - 1));
}

// LAD centerline points (mm) from 20 % to 80 % of its length, and a unit offset direction
// perpendicular to both the vessel and the beam at each
void lad_points(const DetectorGeometry& g, std::vector<Eigen::Vector3d>* p, std::vector<Eigen::Vector3d>* side) {
  const auto& lad = tree().branches[tree().find("LAD")].points;
  for (size_t i = lad.size() / 5; i < lad.size() * 4 / 5; i += 10) {
    const Eigen::Vector3d x = 1000.0 * lad[i].position_m;
    const Eigen::Vector3d t = (lad[i + 1].position_m - lad[i - 1].position_m).normalized();
    const Eigen::Vector3d beam = (x - g.source_mm).normalized();
    p->push_back(x);
    side->push_back(t.cross(beam).normalized());
  }
}

TEST(Fluoroscopy, ContrastLandsOnTheProjectedLadAndNotBeside) {
  FluoroscopyRenderer fr(tree(), noiseless());
  const ContrastInjection inj{.start_s = 0, .duration_s = 2, .volume_ml = 8};
  FluoroFrame before, after;
  fr.render({.time_s = -1, .pose = lao30_cra20(), .wire_m = {}, .injections = {&inj, 1}}, before);
  const Image plain = fr.line_integrals();
  fr.render({.time_s = 1.9, .pose = lao30_cra20(), .wire_m = {}, .injections = {&inj, 1}}, after);
  const Image& filled = fr.line_integrals();
  std::vector<Eigen::Vector3d> p, side;
  lad_points(after.geometry, &p, &side);
  ASSERT_GT(p.size(), 10u);
  int on = 0, off_clean = 0, off_total = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    Eigen::Vector2d cr;
    ASSERT_TRUE(after.geometry.project(p[i], &cr));
    const float d_on = bilinear(filled, cr) - bilinear(plain, cr);
    // iodine 0.12 /mm over a ~2-3 mm chord at ~0.6-0.8 opacity
    if (d_on > 0.05) ++on;
    const uint16_t dark_before = before.pixels[std::lround(cr.y()) * before.width + std::lround(cr.x())];
    const uint16_t dark_after = after.pixels[std::lround(cr.y()) * after.width + std::lround(cr.x())];
    EXPECT_LE(dark_after, dark_before) << "iodine darkens the display";
    for (double sgn : {-1.0, 1.0}) {
      Eigen::Vector2d off;
      ASSERT_TRUE(after.geometry.project(p[i] + sgn * 3.0 * side[i], &off));
      ++off_total;
      if (bilinear(filled, off) - bilinear(plain, off) < 1e-3) ++off_clean;
    }
  }
  EXPECT_EQ(on, static_cast<int>(p.size())) << "every LAD sample darkened";
  // another branch may cross the LAD's shadow here and there
  EXPECT_GE(off_clean, off_total * 8 / 10) << off_clean << " of " << off_total;
  EXPECT_NE(std::find(after.contrast_branches.begin(), after.contrast_branches.end(), "LAD"),
            after.contrast_branches.end());
  EXPECT_TRUE(before.contrast_branches.empty());
}

TEST(Fluoroscopy, ContrastFollowsTheMovedTree) {
  // the beating heart hands the renderer the tree's points where they are now: here the whole
  // tree shifted 6 mm sideways of the beam, so the iodine lands on the shifted LAD, not the old
  FluoroscopyRenderer fr(tree(), noiseless());
  const ContrastInjection inj{.start_s = 0, .duration_s = 2, .volume_ml = 8};
  FluoroFrame plain_frame, frame;
  fr.render({.time_s = -1, .pose = lao30_cra20(), .wire_m = {}, .injections = {&inj, 1}}, plain_frame);
  const Image plain = fr.line_integrals();
  std::vector<Eigen::Vector3d> p, side;
  lad_points(plain_frame.geometry, &p, &side);
  const Eigen::Vector3d shift_mm = 6.0 * side[p.size() / 2];
  std::vector<Eigen::Vector3d> moved;
  for (const auto& b : tree().branches)
    for (const auto& q : b.points) moved.push_back(q.position_m + shift_mm / 1000.0);
  ASSERT_EQ(static_cast<int>(moved.size()), fr.contrast().tree_point_count());
  fr.render({.time_s = 1.9, .pose = lao30_cra20(), .wire_m = {}, .injections = {&inj, 1}, .vessel_points_m = moved},
            frame);
  const Image& filled = fr.line_integrals();
  int on_moved = 0, on_old = 0;
  for (size_t i = p.size() / 3; i < 2 * p.size() / 3; ++i) {
    Eigen::Vector2d at_old, at_new;
    ASSERT_TRUE(frame.geometry.project(p[i], &at_old));
    ASSERT_TRUE(frame.geometry.project(p[i] + shift_mm, &at_new));
    if (bilinear(filled, at_new) - bilinear(plain, at_new) > 0.05) ++on_moved;
    if (bilinear(filled, at_old) - bilinear(plain, at_old) > 0.05) ++on_old;
  }
  EXPECT_GE(on_moved, static_cast<int>(p.size() / 3) - 1);
  EXPECT_LE(on_old, 2);  // another branch may cross here and there
}

TEST(Fluoroscopy, ContrastReachesTheDistalLadLaterThanTheLm) {
  const ContrastBolus bolus(tree(), ContrastBolusSpec{});
  const ContrastInjection inj{.start_s = 0.5, .duration_s = 2, .volume_ml = 8};
  const int lm = tree().find("LM"), lad = tree().find("LAD");
  // first and last segments of each
  double s_lm = -1, s_lad_distal = -1;
  for (const auto& seg : bolus.segments()) {
    if (seg.branch == lm && s_lm < 0) s_lm = seg.s_mm;
    if (seg.branch == lad) s_lad_distal = seg.s_mm;
  }
  ASSERT_GE(s_lm, 0);
  ASSERT_GT(s_lad_distal, 50);
  auto arrival = [&](double s) {
    for (double t = 0; t < 5; t += 0.01) {
      if (bolus.opacity(s, CoronaryOstium::kLeft, t, {&inj, 1}) > 0.05) return t;
    }
    return 99.0;
  };
  const double t_lm = arrival(s_lm), t_distal = arrival(s_lad_distal);
  EXPECT_LT(t_lm, 0.7);
  EXPECT_GT(t_distal, t_lm + 0.2);
  // the front moves at the flow velocity
  EXPECT_NEAR(t_distal - t_lm, (s_lad_distal - s_lm) / bolus.spec().velocity_mm_per_s, 0.05);
  // the right ostium got nothing
  EXPECT_EQ(bolus.opacity(10, CoronaryOstium::kRight, 2.0, {&inj, 1}), 0.0);

  // in frames: at t = start + 0.2 s the LM holds contrast, the distal LAD not yet
  FluoroscopyRenderer fr(tree(), noiseless());
  FluoroFrame f;
  fr.render({.time_s = 0.75, .pose = lao30_cra20(), .wire_m = {}, .injections = {&inj, 1}}, f);
  const auto& bo = fr.contrast().branch_opacity();
  EXPECT_GT(bo[lm], 0.3);
  EXPECT_LT(bo[tree().find("OM2")], 0.05);
  EXPECT_NE(std::find(f.contrast_branches.begin(), f.contrast_branches.end(), "LM"), f.contrast_branches.end());
  EXPECT_EQ(std::find(f.contrast_branches.begin(), f.contrast_branches.end(), "RCA"), f.contrast_branches.end());
}

TEST(Fluoroscopy, ContrastWashesOutAfterTheInjection) {
  FluoroscopyRenderer fr(tree(), noiseless());
  const ContrastInjection inj{.start_s = 0, .duration_s = 2, .volume_ml = 8};
  FluoroFrame f;
  fr.render({.time_s = -1, .pose = lao30_cra20(), .wire_m = {}, .injections = {&inj, 1}}, f);
  const Image plain = fr.line_integrals();
  auto iodine_sum = [&](double t) {
    fr.render({.time_s = t, .pose = lao30_cra20(), .wire_m = {}, .injections = {&inj, 1}}, f);
    double sum = 0;
    for (size_t i = 0; i < plain.pixels.size(); ++i) sum += fr.line_integrals().pixels[i] - plain.pixels[i];
    return sum;
  };
  const double peak = iodine_sum(2.5), later = iodine_sum(4.5), gone = iodine_sum(20);
  EXPECT_GT(peak, 0);
  EXPECT_LT(later, 0.5 * peak) << "1.5 s washout";
  EXPECT_LT(std::abs(gone), 1e-3 * peak);
  EXPECT_TRUE(f.contrast_branches.empty());
}

TEST(Fluoroscopy, WireIsDarkWhereItsPolylineProjects) {
  FluoroscopyRenderer fr(tree(), noiseless());
  const auto& lad = tree().branches[tree().find("LAD")].points;
  std::vector<Eigen::Vector3d> wire_m;
  for (size_t i = 0; i < 80 && i < lad.size(); ++i) wire_m.push_back(lad[i].position_m);  // 40 mm
  FluoroFrame without, with;
  fr.render({.time_s = 0, .pose = lao30_cra20(), .wire_m = {}, .injections = {}}, without);
  fr.render({.time_s = 0, .pose = lao30_cra20(), .wire_m = wire_m, .injections = {}}, with);
  ASSERT_EQ(with.wire_px.size(), wire_m.size());
  EXPECT_TRUE(without.wire_px.empty());
  // the labels are the wire's points in mm projected with the frame's geometry: the ray from the
  // source through the point meets the detector plane at the labelled pixel (pixel (c, r) is centred
  // at centre + (c - (w-1)/2) pixel u + (r - (h-1)/2) pixel v), worked out here from those
  // definitions rather than with DetectorGeometry::project
  const auto& g = with.geometry;
  for (size_t i : {size_t{0}, size_t{40}, wire_m.size() - 1}) {
    const Eigen::Vector3d p = 1000.0 * wire_m[i], n = g.u.cross(g.v).normalized();
    const double t = (g.center_mm - g.source_mm).dot(n) / (p - g.source_mm).dot(n);
    const Eigen::Vector3d hit = g.source_mm + t * (p - g.source_mm);
    const double col = (hit - g.center_mm).dot(g.u) / g.pixel_mm + 0.5 * (g.width - 1);
    const double row = (hit - g.center_mm).dot(g.v) / g.pixel_mm + 0.5 * (g.height - 1);
    EXPECT_NEAR(with.wire_px[i].x(), col, 1e-6) << i;
    EXPECT_NEAR(with.wire_px[i].y(), row, 1e-6) << i;
  }
  int dark = 0, off_line = 0;
  for (int r = 0; r < with.height; ++r) {
    for (int c = 0; c < with.width; ++c) {
      const int i = r * with.width + c;
      if (without.pixels[i] - with.pixels[i] < 500) continue;  // darkened by the wire
      ++dark;
      double best = 1e30;
      for (size_t k = 0; k + 1 < with.wire_px.size(); ++k) {
        const Eigen::Vector2d a = with.wire_px[k], ab = with.wire_px[k + 1] - a, p(c, r);
        const double u = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
        best = std::min(best, (p - a - u * ab).norm());
      }
      if (best > 1.0) ++off_line;  // the 0.36 mm wire is ~0.7 px wide here
    }
  }
  double length_px = 0;
  for (size_t k = 0; k + 1 < with.wire_px.size(); ++k) length_px += (with.wire_px[k + 1] - with.wire_px[k]).norm();
  // the 0.36 mm wire casts a ~0.65 px wide shadow here: that fraction of pixel centres along it
  EXPECT_GT(dark, 0.45 * length_px);
  EXPECT_EQ(off_line, 0);
}

TEST(Fluoroscopy, BackgroundIsReusedForTheSamePoseOnly) {
  FluoroscopyRenderer fr(tree(), noiseless());
  FluoroFrame f;
  const ContrastInjection inj{};
  for (double t : {0.0, 0.5, 1.0}) {
    fr.render({.time_s = t, .pose = lao30_cra20(), .wire_m = {}, .injections = {&inj, 1}}, f);
  }
  EXPECT_EQ(fr.background_renders(), 1);
  fr.render({.time_s = 1.5, .pose = CArmPose{-30, 0, Eigen::Vector3d::Zero()}, .wire_m = {}, .injections = {}}, f);
  EXPECT_EQ(fr.background_renders(), 2);
  fr.render({.time_s = 1.6, .pose = CArmPose{-30, 0, Eigen::Vector3d(0, 0, 5)}, .wire_m = {}, .injections = {}}, f);
  EXPECT_EQ(fr.background_renders(), 3) << "the table moved";
  fr.render({.time_s = 1.7, .pose = CArmPose{-30, 0, Eigen::Vector3d(0, 0, 5)}, .wire_m = {}, .injections = {}}, f);
  EXPECT_EQ(fr.background_renders(), 3);
  fr.invalidate_background();
  fr.render({.time_s = 1.8, .pose = CArmPose{-30, 0, Eigen::Vector3d(0, 0, 5)}, .wire_m = {}, .injections = {}}, f);
  EXPECT_EQ(fr.background_renders(), 4);
  CArmSpec c = small_fluoro_spec().c_arm;
  c.width = c.height = 128;
  c.pixel_mm = 1.6;
  fr.set_c_arm(c);
  fr.render({.time_s = 1.9, .pose = CArmPose{-30, 0, Eigen::Vector3d(0, 0, 5)}, .wire_m = {}, .injections = {}}, f);
  EXPECT_EQ(fr.background_renders(), 5);
  EXPECT_EQ(f.width, 128);
  EXPECT_EQ(f.pixels.size(), 128u * 128u);
  // a reused background gives the same anatomy as a fresh projection
  FluoroscopyRenderer fresh(tree(), noiseless());
  fresh.set_c_arm(c);
  FluoroFrame g;
  fresh.render({.time_s = 1.9, .pose = CArmPose{-30, 0, Eigen::Vector3d(0, 0, 5)}, .wire_m = {}, .injections = {}}, g);
  fr.render({.time_s = 1.9, .pose = CArmPose{-30, 0, Eigen::Vector3d(0, 0, 5)}, .wire_m = {}, .injections = {}}, f);
  EXPECT_EQ(f.pixels, g.pixels);
}

// relative RMS difference of two line-integral images (relative to b's largest value)
double relative_rms(const Image& a, const Image& b) {
  double sum = 0, top = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    sum += std::pow(double(a.pixels[i]) - b.pixels[i], 2);
    top = std::max(top, std::abs(double(b.pixels[i])));
  }
  return std::sqrt(sum / a.pixels.size()) / top;
}

TEST(Fluoroscopy, AMoveShowsAQuickProjectionOfTheNewPoseThenTheWholeOne) {
  const CArmPose before = lao30_cra20(), after{-30, 0, Eigen::Vector3d::Zero()};
  // the references: whole projections of both poses by a renderer without the quick one
  FluoroscopyRenderer whole(tree(), noiseless());
  FluoroFrame f;
  whole.render({.pose = before}, f);
  const Image at_before = whole.line_integrals();
  whole.render({.pose = after}, f);
  const Image at_after = whole.line_integrals();
  EXPECT_EQ(whole.work_ahead(), 0) << "without set_move_preview the projection is whole at once";

  FluoroscopyRenderer fr(tree(), noiseless());
  fr.set_move_preview({.stride = 4, .rows_per_step = 64});
  fr.render({.pose = before}, f);
  while (fr.work_ahead() > 0) {}
  fr.render({.pose = after}, f);
  EXPECT_FALSE(fr.background_refined());
  // the first frame after the move: the new pose, coarser (1/16 of the rays), not the old pose
  const double quick_err = relative_rms(fr.line_integrals(), at_after);
  const double stale_err = relative_rms(fr.line_integrals(), at_before);
  std::printf("quick projection against the whole one: %.3g %% RMS (the pose before: %.3g %%)\n", 100 * quick_err,
              100 * stale_err);
  EXPECT_LT(quick_err, 0.02);
  EXPECT_LT(quick_err, 0.25 * stale_err);
  // then one band of 64 rows per call: the 256 rows in four, the last swapping the whole one in
  for (int band = 0; band < 4; ++band) {
    EXPECT_FALSE(fr.background_refined()) << band;
    EXPECT_EQ(fr.work_ahead(), 1) << band;
  }
  EXPECT_TRUE(fr.background_refined());
  EXPECT_EQ(fr.work_ahead(), 0);
  fr.render({.pose = after}, f);
  // the bands' rays are the whole detector's (their pixel centres computed from another centre)
  EXPECT_LT(relative_rms(fr.line_integrals(), at_after), 1e-6);
  EXPECT_EQ(fr.background_renders(), 2) << "a refinement is not another pose";
  EXPECT_THROW(fr.set_move_preview({.stride = 0, .rows_per_step = 64}), std::invalid_argument);
  EXPECT_THROW(fr.set_move_preview({.stride = 4, .rows_per_step = 0}), std::invalid_argument);
}

// the displayed frame, not only the line integrals: the quick frame (1/64 of the rays at the
// default stride 8; here a 32^2 grid under 256^2) is windowed on itself and stays close to the
// whole projection's frame; once refined, its window is found again and the frame is the whole one's
double display_rms(const FluoroFrame& a, const FluoroFrame& b) {
  double sum = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) sum += std::pow((double(a.pixels[i]) - b.pixels[i]) / 65535.0, 2);
  return std::sqrt(sum / a.pixels.size());
}

TEST(Fluoroscopy, TheQuickFrameIsWindowedAsTheWholeOne) {
  const CArmPose before = lao30_cra20(), after{-30, 0, Eigen::Vector3d::Zero()};
  FluoroscopyRenderer whole(tree(), noiseless());
  FluoroFrame at_before, at_after, f;
  whole.render({.pose = before}, at_before);
  whole.render({.pose = after}, at_after);
  // as the x-ray loop does: the first pose whole, the quick projection from the first move on
  FluoroscopyRenderer fr(tree(), noiseless());
  fr.render({.pose = before}, f);
  EXPECT_LT(display_rms(f, at_before), 1e-6);
  fr.set_move_preview(MovePreview{});
  ASSERT_EQ(MovePreview{}.stride, 8);
  fr.render({.pose = after}, f);
  const double quick = display_rms(f, at_after), stale = display_rms(f, at_before);
  while (fr.work_ahead() > 0) {}
  fr.render({.pose = after}, f);
  const double refined = display_rms(f, at_after);
  std::printf(
      "displayed frame against the whole projection's, RMS of full scale: quick %.4f (the pose before "
      "%.4f), refined %.4f\n",
      quick, stale, refined);
  EXPECT_LT(quick, 0.03);
  EXPECT_LT(quick, 0.25 * stale);
  int worst_step = 0;
  for (size_t i = 0; i < f.pixels.size(); ++i)
    worst_step = std::max(worst_step, std::abs(int(f.pixels[i]) - int(at_after.pixels[i])));
  EXPECT_LE(worst_step, 1) << "every pixel within a display step of the whole frame's (refined RMS " << refined << ")";
}

TEST(Fluoroscopy, QuantumNoiseIsPoisson) {
  FluoroSpec s = small_fluoro_spec();
  s.photons_per_pixel = 2000;
  s.blur_sigma_px = 0;
  FluoroscopyRenderer fr(tree(), s);
  FluoroFrame f;
  fr.render({.time_s = 0, .pose = lao30_cra20(), .wire_m = {}, .injections = {}}, f);
  const Image a = fr.detector_counts();
  fr.render({.time_s = 0, .pose = lao30_cra20(), .wire_m = {}, .injections = {}}, f);
  const Image& b = fr.detector_counts();
  const Image& line = fr.line_integrals();
  // two frames of the same scene: var(a - b) = 2 lambda per pixel; split by the count regime
  double lam_lo = 0, var_lo = 0, lam_hi = 0, var_hi = 0, mean_diff = 0;
  int n_lo = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const double lambda = 2000.0 * std::exp(-static_cast<double>(line.pixels[i]));
    const double d = a.pixels[i] - b.pixels[i];
    mean_diff += a.pixels[i] - lambda;
    if (lambda < 30) {
      lam_lo += lambda;
      var_lo += 0.5 * d * d;
      ++n_lo;
    } else {
      lam_hi += lambda;
      var_hi += 0.5 * d * d;
    }
  }
  ASSERT_GT(n_lo, 500) << "the phantom has dense regions below 30 quanta";
  EXPECT_NEAR(var_lo / lam_lo, 1.0, 0.05);
  EXPECT_NEAR(var_hi / lam_hi, 1.0, 0.05);
  EXPECT_NEAR(mean_diff / (lam_lo + lam_hi), 0.0, 0.01) << "unbiased";
  EXPECT_NE(a.pixels, b.pixels) << "fresh noise each frame";
}

TEST(Fluoroscopy, PoissonSamplerMatchesMeanAndVariance) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (double lambda : {0.5, 5.0, 29.0, 31.0, 500.0}) {
    double sum = 0, sum2 = 0;
    const int n = 100000;
    for (int i = 0; i < n; ++i) {
      const double k = poisson_sample(lambda, u(rng), u(rng));
      sum += k;
      sum2 += k * k;
    }
    const double mean = sum / n, var = sum2 / n - mean * mean;
    EXPECT_NEAR(mean, lambda, 5 * std::sqrt(lambda / n)) << lambda;
    EXPECT_NEAR(var / lambda, 1.0, 0.03) << lambda;
  }
}

TEST(Fluoroscopy, BlurLowersTheNoiseByTheKernelsEnergy) {
  FluoroSpec s = small_fluoro_spec();
  s.photons_per_pixel = 2000;
  s.blur_sigma_px = 1.0;
  FluoroscopyRenderer fr(tree(), s);
  FluoroFrame f;
  const CArmPose pose{0, 0, Eigen::Vector3d(0, 0, 400)};  // above the shoulders: mostly air
  fr.render({.time_s = 0, .pose = pose, .wire_m = {}, .injections = {}}, f);
  const Image a = fr.detector_counts();
  fr.render({.time_s = 0, .pose = pose, .wire_m = {}, .injections = {}}, f);
  double var = 0, lam = 0;
  int n = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    if (fr.line_integrals().pixels[i] != 0) continue;  // flat air only
    const double d = a.pixels[i] - fr.detector_counts().pixels[i];
    var += 0.5 * d * d;
    lam += 2000;
    ++n;
  }
  ASSERT_GT(n, 10000);
  // sum of the squared 2D weights of a sampled sigma-1 Gaussian: (sum_i g_i^2)^2
  double s1 = 0, s2 = 0;
  for (int i = -3; i <= 3; ++i) {
    s1 += std::exp(-0.5 * i * i);
  }
  for (int i = -3; i <= 3; ++i) s2 += std::pow(std::exp(-0.5 * i * i) / s1, 2);
  EXPECT_NEAR(var / lam, s2 * s2, 0.1 * s2 * s2);
}

TEST(Fluoroscopy, SameSeedSameFramesOtherSeedOtherNoise) {
  FluoroSpec s = small_fluoro_spec();
  const ContrastInjection inj{};
  const FluoroInput in{.time_s = 1.0, .pose = lao30_cra20(), .wire_m = {}, .injections = {&inj, 1}};
  FluoroscopyRenderer a(tree(), s), b(tree(), s);
  FluoroFrame fa, fb;
  for (int i = 0; i < 2; ++i) {
    a.render(in, fa);
    b.render(in, fb);
    EXPECT_EQ(fa.pixels, fb.pixels);
  }
  s.seed = 2;
  FluoroscopyRenderer c(tree(), s);
  FluoroFrame fc;
  c.render(in, fc);
  EXPECT_NE(fa.pixels, fc.pixels);
}

}  // namespace
}  // namespace pcisim::xray

namespace pcisim::xray {
namespace {

TEST(Fluoroscopy, NonFiniteInputsGiveAFrameNotACrash) {
  FluoroscopyRenderer fr(tree(), small_fluoro_spec());
  FluoroFrame f;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(fr.render({.time_s = 0, .pose = CArmPose{nan, 0, Eigen::Vector3d::Zero()}}, f), std::invalid_argument)
      << "no pose to fall back on yet";
  fr.render({.time_s = 0, .pose = lao30_cra20()}, f);
  const ContrastInjection bad[2] = {{.start_s = nan}, {.start_s = 0, .duration_s = 2, .volume_ml = 8}};
  std::vector<Eigen::Vector3d> wire_m = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(nan, 0, 0),
                                         Eigen::Vector3d(0.001, 0, 0), Eigen::Vector3d(0.002, 0, 0)};
  fr.render({.time_s = 1, .pose = CArmPose{30, nan, Eigen::Vector3d::Zero()}, .wire_m = wire_m, .injections = bad}, f);
  EXPECT_EQ(fr.background_renders(), 1) << "the last pose was kept";
  EXPECT_EQ(f.pose.primary_deg, 30);
  EXPECT_EQ(f.pose.secondary_deg, 20);
  for (float v : fr.line_integrals().pixels) ASSERT_TRUE(std::isfinite(v));
  EXPECT_FALSE(f.contrast_branches.empty()) << "the good injection still shows";
  fr.render({.time_s = nan, .pose = lao30_cra20(), .wire_m = wire_m, .injections = bad}, f);
  EXPECT_TRUE(f.contrast_branches.empty());
  for (float v : fr.line_integrals().pixels) ASSERT_TRUE(std::isfinite(v));
  EXPECT_EQ(f.wire_px.size(), 4u);
  EXPECT_TRUE(std::isnan(f.wire_px[1].x()));
  // a node blown kilometres away (a physics blow-up) and one just beside the source: their
  // shadows would span billions of pixels; the frame is still made and finite
  const std::vector<Eigen::Vector3d> wild_m = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(3e3, -2e3, 1e3),
                                               1e-3 * (f.geometry.source_mm + Eigen::Vector3d(1e-6, 1e-6, 1e-6)),
                                               Eigen::Vector3d(0.002, 0, 0)};
  fr.render({.time_s = 2, .pose = lao30_cra20(), .wire_m = wild_m}, f);
  for (float v : fr.line_integrals().pixels) ASSERT_TRUE(std::isfinite(v));
  EXPECT_EQ(f.wire_px.size(), 4u);
}

}  // namespace
}  // namespace pcisim::xray
