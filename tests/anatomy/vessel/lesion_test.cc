// QCA on a radius profile (anatomy/vessel/lesion.h) against profiles whose lesion is known exactly:
// a raised-cosine narrowing on a tapering vessel, two on one branch, a healthy taper and a mild
// narrowing (none), and the painted stenosis of the CTA phantoms (their truth trees).
#include "anatomy/vessel/lesion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "anatomy/phantom/phantom_cta.h"

namespace pcisim::anatomy {
namespace {

struct Narrowing {
  double centre_mm, length_mm, fraction;
};

// a straight branch of `length_mm` at 0.5 mm points, its radius tapering linearly from r0 to r1 mm,
// narrowed by raised cosines r (1 - f (1 + cos(2 pi x / L)) / 2) over |x| <= L / 2
VesselTree tube(double length_mm, double r0_mm, double r1_mm, const std::vector<Narrowing>& narrowings) {
  VesselTree t;
  VesselBranch b;
  b.name = "LAD";
  for (double s = 0.0; s <= length_mm + 1e-9; s += 0.5) {
    double r = r0_mm + (r1_mm - r0_mm) * s / length_mm;
    for (const Narrowing& n : narrowings) {
      const double x = (s - n.centre_mm) / n.length_mm;
      if (std::abs(x) <= 0.5) r *= 1.0 - n.fraction * 0.5 * (1.0 + std::cos(2.0 * std::numbers::pi * x));
    }
    b.points.push_back({Eigen::Vector3d(s * 1e-3, 0.0, 0.0), r * 1e-3});
  }
  t.branches.push_back(b);
  return t;
}

// the extent narrowed by at least 10 % of a raised cosine of length L and fraction f
double extent_mm(double length_mm, double f) {
  return length_mm / std::numbers::pi * std::acos(2.0 * 0.1 / f - 1.0);
}

TEST(Lesion, ARaisedCosineNarrowingOnATaperIsMeasuredAgainstTheTaper) {
  const VesselTree t = tube(60.0, 2.0, 1.4, {{25.0, 8.0, 0.6}});
  const std::vector<Lesion> found = detect_lesions(t);
  ASSERT_EQ(found.size(), 1u);
  const Lesion& l = found[0];
  const double reference_mm = 2.0 * (2.0 + (1.4 - 2.0) * 25.0 / 60.0);
  EXPECT_EQ(l.branch, "LAD");
  EXPECT_NEAR(l.position_mm, 25.0, 1e-9);
  EXPECT_NEAR(l.reference_diameter_mm, reference_mm, 0.01 * reference_mm);
  EXPECT_NEAR(l.minimal_lumen_diameter_mm, 0.4 * reference_mm, 1e-9);
  EXPECT_NEAR(l.diameter_stenosis_pct, 60.0, 1.0);
  EXPECT_NEAR(l.length_mm, extent_mm(8.0, 0.6), 0.5) << "the points narrowed 10 % or more, 0.5 mm apart";
  EXPECT_EQ(validate_lesion(l, t), "");
}

TEST(Lesion, TwoNarrowingsOnABranchAreTwoLesionsInOrder) {
  const VesselTree t = tube(80.0, 1.8, 1.5, {{20.0, 6.0, 0.5}, {55.0, 10.0, 0.75}});
  const std::vector<Lesion> found = detect_lesions(t);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_NEAR(found[0].position_mm, 20.0, 1e-9);
  EXPECT_NEAR(found[0].diameter_stenosis_pct, 50.0, 1.0);
  EXPECT_NEAR(found[1].position_mm, 55.0, 1e-9);
  EXPECT_NEAR(found[1].diameter_stenosis_pct, 75.0, 1.0);
}

TEST(Lesion, AHealthyTaperAndAMildNarrowingAreNone) {
  EXPECT_TRUE(detect_lesions(tube(60.0, 2.2, 1.0, {})).empty()) << "a taper is not a lesion";
  EXPECT_TRUE(detect_lesions(tube(60.0, 2.0, 1.6, {{30.0, 8.0, 0.2}})).empty()) << "20 %: under the 30 % reported";
  LesionDetection milder;
  milder.min_stenosis_pct = 15.0;
  EXPECT_EQ(detect_lesions(tube(60.0, 2.0, 1.6, {{30.0, 8.0, 0.2}}), milder).size(), 1u);
  EXPECT_TRUE(detect_lesions(tube(4.0, 2.0, 2.0, {{2.0, 2.0, 0.9}})).empty()) << "too short a branch to refer to";
  // a narrowing that reaches within 2 mm of the branch's start or end has no healthy wall beyond it
  EXPECT_TRUE(detect_lesions(tube(40.0, 2.0, 1.6, {{1.5, 4.0, 0.6}})).empty()) << "at the ostium";
  EXPECT_TRUE(detect_lesions(tube(40.0, 2.0, 1.6, {{39.0, 4.0, 0.6}})).empty()) << "at the end";
  EXPECT_EQ(detect_lesions(tube(40.0, 2.0, 1.6, {{6.0, 4.0, 0.6}})).size(), 1u) << "clear of both";
}

TEST(Lesion, AValidatorNamesTheFieldThatDoesNotFit) {
  const VesselTree t = tube(60.0, 2.0, 1.6, {});
  Lesion l{"LAD", 30.0, 6.0, 1.2, 3.6, 100.0 * (1.0 - 1.2 / 3.6), 0.2, 0.5};
  EXPECT_EQ(validate_lesion(l, t), "");
  auto bad = [&](auto change) {
    Lesion b = l;
    change(b);
    return validate_lesion(b, t);
  };
  EXPECT_EQ(bad([](Lesion& b) { b.branch = "RCA"; }).rfind("branch:", 0), 0u);
  EXPECT_EQ(bad([](Lesion& b) { b.position_mm = 61.0; }).rfind("position_mm:", 0), 0u);
  EXPECT_EQ(bad([](Lesion& b) { b.minimal_lumen_diameter_mm = 4.0; }).rfind("minimal_lumen_diameter_mm:", 0), 0u);
  EXPECT_EQ(bad([](Lesion& b) { b.diameter_stenosis_pct = 50.0; }).rfind("diameter_stenosis_pct:", 0), 0u);
  EXPECT_EQ(bad([](Lesion& b) { b.reference_diameter_mm = NAN; }).rfind("reference_diameter_mm:", 0), 0u);
  EXPECT_EQ(bad([](Lesion& b) { b.calcified_fraction = 1.5; }).rfind("calcified_fraction:", 0), 0u);
}

// the CTA phantoms' truth trees: the painted stenosis found where it was painted, as severe and as
// long; QCA on the rest of the tree (tapers, branch points, the aorta) reports nothing else
TEST(Lesion, ThePhantomsPaintedStenosisIsFoundOnItsTruthTree) {
  for (uint32_t seed : {1u, 2u, 3u, 4u}) {
    PhantomCtaSpec spec;
    spec.seed = seed;
    spec.dims = {96, 96, 96};
    spec.spacing_mm = {1.4, 1.4, 1.4};
    const PhantomCta p = make_phantom_cta(spec);
    const std::vector<Lesion> truth = phantom_cta_lesions(p);
    ASSERT_EQ(truth.size(), 1u) << "seed " << seed;
    EXPECT_EQ(validate_lesion(truth[0], p.truth), "") << "seed " << seed;
    const std::vector<Lesion> found = detect_lesions(p.truth);
    int matched = 0;
    for (const Lesion& l : found) {
      if (l.branch != truth[0].branch || std::abs(l.position_mm - truth[0].position_mm) > 2.0) {
        ADD_FAILURE() << "seed " << seed << ": a lesion the phantom did not paint: " << l.branch << " at "
                      << l.position_mm << " mm, " << l.diameter_stenosis_pct << " %";
        continue;
      }
      ++matched;
      EXPECT_NEAR(l.position_mm, truth[0].position_mm, 0.6) << "seed " << seed;
      EXPECT_NEAR(l.diameter_stenosis_pct, truth[0].diameter_stenosis_pct, 3.0) << "seed " << seed;
      EXPECT_NEAR(l.reference_diameter_mm, truth[0].reference_diameter_mm, 0.05 * truth[0].reference_diameter_mm)
          << "seed " << seed;
      EXPECT_NEAR(l.length_mm, truth[0].length_mm, 1.5) << "seed " << seed;
    }
    EXPECT_EQ(matched, 1) << "seed " << seed;
  }
}

}  // namespace
}  // namespace pcisim::anatomy
