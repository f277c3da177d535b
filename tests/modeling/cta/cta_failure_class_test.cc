// The CTA pipeline on the phantom family's failure classes (issue #30, docs/modeling.md): one
// family member per class with the class's hard end pinned (PhantomCtaSpec::pins), modelled from
// the aortic seed alone and scored against its exact truth (Schaap et al. 2009, as the bench
// scores: modeling/evaluation/centerline_scores.h). Each asserts what surviving the class means:
// the four main vessels named on the truth, most of the tree found, little centerline that is no
// vessel. The seeds are tuning seeds (anatomy/phantom/phantom_cta.h); the held-out split is the
// bench's (docs/benchmarks/model-family.md).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "anatomy/phantom/phantom_cta.h"
#include "modeling/cta/cta_pipeline.h"
#include "modeling/evaluation/centerline_scores.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

// a family member over the heart and its vessels (130 x 130 x 115 mm), its scan and contrast
// moderate (0.6 mm isotropic voxels, 25 HU of noise, myocardium 70 HU, lumen falling 1.5 HU/mm) so
// that each test is about its class alone
anatomy::PhantomCtaSpec member(uint32_t seed, double voxel_mm = 0.6, double noise_hu = 25) {
  anatomy::PhantomCtaSpec s = anatomy::family_phantom_cta_spec(seed);
  s.spacing_mm = Vector3d::Constant(voxel_mm);
  for (int a = 0; a < 3; ++a) s.dims[a] = std::lround(Vector3d(130, 130, 115)[a] / voxel_mm);
  s.noise_sigma_hu = noise_hu;
  s.pins.myocardium_hu = 70;
  s.pins.fade_hu_per_mm = 1.5;
  return s;
}

struct Outcome {
  CenterlineScores scores;
  double false_mm = 0, missed_mm = 0;
  std::string missing;  // the main vessels the model does not find (most of them)
};

// the pipeline at its defaults (no lumen surface, no heart fit: the centerlines are what is scored)
Outcome model(const anatomy::PhantomCtaSpec& spec, const char* name) {
  const anatomy::PhantomCta cta = anatomy::make_phantom_cta(spec);
  CtaPipelineOptions o;
  o.loft = false;
  o.heart_fit.enabled = false;
  const CtaModel m = build_cta_model(cta.ct, {cta.aortic_seed_mm}, o);
  Outcome out;
  out.scores = score_centerlines(outside_aorta(cta.truth, cta.truth), outside_aorta(m.model.vessels, cta.truth));
  const double step_mm = CenterlineScoreOptions{}.sample_spacing_m * 1e3;
  out.false_mm = out.scores.fp * step_mm;
  out.missed_mm = out.scores.fn * step_mm;
  // a main vessel is found when at least half of it is (Schaap's per-vessel OV, from its ostium)
  for (const char* v : {"LAD", "LCx", "RCA"}) {
    for (const VesselScores& vs : out.scores.vessels) {
      if (vs.name == v && !(vs.ov >= 0.5))
        out.missing += fmt::format("{}{} (OV {:.2f})", out.missing.empty() ? "" : ", ", v, vs.ov);
    }
  }
  std::printf("%s (seed %u, %.2f mm, noise %.0f HU): OV %.3f OT %.3f AI %.3f mm, false %.0f mm, missed %.0f mm%s%s\n",
              name, spec.seed, spec.spacing_mm.x(), spec.noise_sigma_hu, out.scores.ov, out.scores.ot, out.scores.ai_mm,
              out.false_mm, out.missed_mm, out.missing.empty() ? "" : "; not found: ", out.missing.c_str());
  return out;
}

// what surviving a class means here: the tree is modelled from the one seed (no "no coronary artery
// found"), the three main vessels are found, most of the tree is (OV >= 0.80), and the false
// centerline stays within 150 mm (a sponge through a chamber, the rim of a large lumen or a vein
// traced as a tree is hundreds). The targets are stricter (held-out OV >= 0.95 at the
// median, false <= 40 mm at worst) and are not met: docs/benchmarks/model-family.md; measured on
// these six, 2026-11-29: OV 0.85-0.96, false 14-121 mm
void expect_survives(const Outcome& o) {
  EXPECT_EQ(o.missing, "");
  EXPECT_GE(o.scores.ov, 0.80);
  EXPECT_LE(o.false_mm, 150.0);
}

// the aortic valve open: the left ventricle's contrast joins the aortic root (a systolic phase);
// the fill takes the chamber in and clipping must cut it away by its shape
TEST(CtaFailureClass, AnOpenValveLeavesTheVentricleOutOfTheTree) {
  anatomy::PhantomCtaSpec s = member(21);
  s.pins.open_valve = 1;
  s.pins.rv_hu = 350;
  expect_survives(model(s, "open valve"));
}

// a thin right-ventricular free wall (2 mm) over an enhanced right ventricle: the RCA runs in fat
// on it, a partial volume's reach from a bright chamber
TEST(CtaFailureClass, AThinRightVentricularWallKeepsTheRcaApartFromTheVentricle) {
  anatomy::PhantomCtaSpec s = member(22);
  s.pins.rv_wall_mm = 2;
  s.pins.rv_hu = 400;
  expect_survives(model(s, "thin RV wall"));
}

// veins as bright as a distal artery (300 HU) touching arteries beside and across them
TEST(CtaFailureClass, TouchingVeinsAreNotTracedAsArteries) {
  anatomy::PhantomCtaSpec s = member(23);
  s.pins.vein_hu = 300;
  expect_survives(model(s, "touching veins"));
}

// low contrast: 300 HU at the ostia, falling 3 HU/mm to 250 (the family's floor), over a 100 HU
// myocardium
TEST(CtaFailureClass, LowContrastStillGivesTheTree) {
  anatomy::PhantomCtaSpec s = member(24);
  s.pins.contrast_hu_proximal = 300;
  s.pins.fade_hu_per_mm = 3;
  s.pins.myocardium_hu = 100;
  expect_survives(model(s, "low contrast"));
}

// high noise: 45 HU (the family's most), the fill's threshold pushed up toward the distal lumen
TEST(CtaFailureClass, HighNoiseStillGivesTheTree) {
  expect_survives(model(member(25, 0.6, 45), "high noise"));
}

// 0.8 mm voxels (the family's coarsest, across slices too): a 0.7 mm branch is under one voxel
TEST(CtaFailureClass, CoarseVoxelsStillGiveTheTree) {
  expect_survives(model(member(26, 0.8), "0.8 mm voxels"));
}

// the right heart's blood near the lower threshold under high noise: family seed 15 as the bench
// makes it (0.52 mm voxels, right atrium 207 HU, 41 HU of noise, threshold 183 HU). The fill
// strings the right atrium into a sponge, clipping cuts it away and the RCA that runs on it with
// it, and a 28 mm fragment by the root is kept as the second tree; the fill again on the smoothed
// CT finds the RCA (RefillOptions::short_tree_mm; without it OV 0.61, the RCA not found). (Cropped
// to the heart at 0.6 mm, as the tests above are, the fill kept the RCA either way.)
TEST(CtaFailureClass, ARightHeartAtTheThresholdDoesNotTakeTheRca) {
  expect_survives(model(anatomy::family_phantom_cta_spec(15), "right heart at the threshold"));
}

}  // namespace
}  // namespace pcisim::modeling
