// Stage (g), the elastic part: the placed template heart fitted to the CT's heart. The phantom CTAs
// paint the heart as a sphere of myocardium (radius 50 mm times the drawn scale, about the drawn
// centre; the chambers inside it) in pericardial fat, so every epicardial vertex has an exact
// distance to the truth. The template differs from it by its atrial bulges (up to 14 mm) and by
// what the placement from the vessels leaves (a few mm and degrees).
#include "modeling/heart/heart_elastic_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "anatomy/heart/template_heart_surface.h"
#include "anatomy/phantom/phantom_cta.h"
#include "anatomy/phantom/thorax_phantom.h"
#include "modeling/heart/heart_placement.h"
#include "realtime/percentile.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

// the heart of a phantom CTA at 1 mm voxels (the fit averages to 1 mm blocks anyway)
anatomy::PhantomCta heart_cta(uint32_t seed, double noise_hu = 25) {
  anatomy::PhantomCtaSpec spec;
  spec.seed = seed;
  spec.dims = {130, 130, 125};
  spec.spacing_mm = Vector3d(1.0, 1.0, 1.0);
  spec.noise_sigma_hu = noise_hu;
  return anatomy::make_phantom_cta(spec);
}

struct SurfaceError {
  double mean_mm = 0, p95_mm = 0, max_mm = 0;
};

// distance to the painted heart over the epicardial vertices (template-frame vertices, posed)
SurfaceError against_truth(const anatomy::PhantomCta& cta, const anatomy::HeartPose& pose,
                           const Eigen::Matrix3Xd& v_m) {
  std::vector<double> d;
  for (int i : anatomy::marked_surface_vertices(anatomy::template_heart_mesh(), anatomy::kEpicardium))
    d.push_back(anatomy::distance_to_painted_heart_mm(cta.facts, 1e3 * pose.to_case(v_m.col(i))));
  SurfaceError e;
  for (double x : d) e.mean_mm += x / double(d.size());
  e.p95_mm = realtime::percentile(d, 0.95);
  e.max_mm = realtime::percentile(d, 1.0);
  return e;
}

TEST(HeartElasticFit, TheTemplatePlacedUnderTheVesselsIsFittedToThePaintedHeart) {
  for (uint32_t seed : {1u, 3u}) {
    const anatomy::PhantomCta cta = heart_cta(seed);
    const HeartPlacement placed = place_template_heart(cta.truth, HeartPlacementOptions{});
    const HeartElasticFitOptions o;
    const HeartElasticFit fit = fit_heart_elastic(cta.ct, cta.truth, placed.pose, anatomy::template_heart_mesh(), o);
    const SurfaceError before = against_truth(cta, placed.pose, anatomy::template_heart_mesh().vertices_m);
    const SurfaceError after = against_truth(cta, placed.pose, fit.vertices_m);
    const double true_ml =
        4.0 / 3.0 * M_PI * std::pow(anatomy::kPhantomHeartRadiusMm * cta.facts.heart_scale, 3) / 1000.0;
    std::printf(
        "phantom %u: epicardium to the true heart, placed %.2f / %.2f / %.2f mm (mean / p95 / max), fitted %.2f / "
        "%.2f / %.2f mm; %d of %d vertices found the outline (%d outliers), moved %.2f mm mean, %.1f max; backoff "
        "%.2f, smallest tet %.0f %%; %.0f -> %.0f ml (true sphere %.0f ml)\n",
        seed, before.mean_mm, before.p95_mm, before.max_mm, after.mean_mm, after.p95_mm, after.max_mm, fit.targets,
        fit.epicardial_vertices, fit.outliers, fit.move_mean_mm, fit.move_max_mm, fit.backoff,
        100 * fit.min_tet_volume_ratio, fit.volume_placed_ml, fit.volume_fitted_ml, true_ml);
    // the atrial bulges come down, the rest stays where the placement put it (already close)
    EXPECT_LT(after.max_mm, 0.6 * before.max_mm) << "phantom " << seed;
    EXPECT_LT(after.p95_mm, 0.5 * before.p95_mm) << "phantom " << seed;
    EXPECT_LT(after.mean_mm, 0.7 * before.mean_mm) << "phantom " << seed;
    EXPECT_LT(after.mean_mm, 0.5) << "phantom " << seed;
    EXPECT_LT(after.p95_mm, 2.0) << "phantom " << seed;
    // and the volume it encloses is the painted heart's within 2 %
    EXPECT_LT(std::abs(fit.volume_fitted_ml - true_ml), 0.02 * true_ml) << "phantom " << seed;
    EXPECT_GE(fit.min_tet_volume_ratio, o.min_tet_volume_fraction);
    EXPECT_TRUE(fit.notes.empty());
  }
}

TEST(HeartElasticFit, ACtWithoutAHeartLeavesTheTemplateAsPlacedAndSaysSo) {
  // fat everywhere: no outline to find
  const anatomy::PhantomCta cta = heart_cta(1, 0);
  anatomy::Volume fat = cta.ct;
  std::fill(fat.hu_i16.begin(), fat.hu_i16.end(), int16_t{-100});
  const HeartPlacement placed = place_template_heart(cta.truth, HeartPlacementOptions{});
  const HeartElasticFit fit =
      fit_heart_elastic(fat, cta.truth, placed.pose, anatomy::template_heart_mesh(), HeartElasticFitOptions{});
  EXPECT_EQ(fit.rounds_run, 0);
  ASSERT_EQ(fit.notes.size(), 1u);
  EXPECT_NE(fit.notes[0].find("outline was found from 0 of"), std::string::npos) << fit.notes[0];
  EXPECT_LT((fit.vertices_m - anatomy::template_heart_mesh().vertices_m).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(HeartElasticFit, AHeartOutsideTheCtIsRefusedWithTheAxis) {
  const anatomy::PhantomCta cta = heart_cta(1, 0);
  anatomy::HeartPose far;
  far.translation_m = Vector3d(2.0, 0, 0);  // 2 m to the left
  try {
    fit_heart_elastic(cta.ct, cta.truth, far, anatomy::template_heart_mesh(), HeartElasticFitOptions{});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("outside the CT"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pcisim::modeling
