// Schaap's centerline measures on trees of straight branches whose answers follow from lengths and
// radii: a tree against itself, shifted off its centerline, cut short, with a spurious branch,
// with a thin branch (left out of OT), with a stenosis (kept in OT), with radii scaled.
#include "modeling/evaluation/centerline_scores.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace pcisim::modeling {
namespace {

using anatomy::VesselBranch;
using anatomy::VesselTree;
using Eigen::Vector3d;

constexpr double kMm = 1e-3;

// a straight branch from a_mm to b_mm with a point every step_mm and radius r_mm
VesselBranch straight(const char* name, int parent, int parent_point, const Vector3d& a_mm, const Vector3d& b_mm,
                      double r_mm, double step_mm = 1.0) {
  VesselBranch br{name, parent, parent_point, {}};
  const int n = static_cast<int>(std::lround((b_mm - a_mm).norm() / step_mm));
  for (int i = 0; i <= n; ++i) br.points.push_back({(a_mm + (b_mm - a_mm) * i / n) * kMm, r_mm * kMm});
  return br;
}

// an aorta (left out), LM 10 mm splitting into LAD 40 mm and LCx 30 mm, D1 20 mm off the LAD at
// 10 mm, and a thin OM1 (diameter 1.2 mm) 20 mm off the LCx at 15 mm; all in the plane z = 0.
// Branches: 120 mm. Vessels (ostium to end): LAD 50, LCx 40, D1 40, OM1 45 mm.
VesselTree tree() {
  VesselTree t;
  t.branches.push_back(straight("aorta", -1, -1, {-15, 0, -20}, {-15, 0, 20}, 12));
  t.branches.push_back(straight("LM", 0, 20, {0, 0, 0}, {10, 0, 0}, 2.0));
  t.branches.push_back(straight("LAD", 1, 10, {10, 0, 0}, {50, 0, 0}, 1.5));
  t.branches.push_back(straight("LCx", 1, 10, {10, 0, 0}, {10, 30, 0}, 1.25));
  t.branches.push_back(straight("D1", 2, 10, {20, 0, 0}, {20, -20, 0}, 1.0));
  t.branches.push_back(straight("OM1", 3, 15, {10, 15, 0}, {30, 15, 0}, 0.6));
  return t;
}
constexpr double kTreeMm = 120;

VesselTree shifted(VesselTree t, const Vector3d& by_mm) {
  for (auto& b : t.branches) {
    for (auto& p : b.points) p.position_m += by_mm * kMm;
  }
  return t;
}

const VesselScores& vessel(const CenterlineScores& s, const std::string& name) {
  const auto it = std::find_if(s.vessels.begin(), s.vessels.end(), [&](const auto& v) { return v.name == name; });
  EXPECT_NE(it, s.vessels.end()) << name;
  return *it;
}

TEST(CenterlineScores, IdenticalTreesScorePerfectly) {
  const CenterlineScores s = score_centerlines(tree(), tree());
  EXPECT_DOUBLE_EQ(s.ov, 1.0);
  EXPECT_DOUBLE_EQ(s.of, 1.0);
  EXPECT_DOUBLE_EQ(s.ot, 1.0);
  EXPECT_NEAR(s.ai_mm, 0.0, 1e-9);
  EXPECT_NEAR(s.radius_error_mean_mm, 0.0, 1e-9);
  EXPECT_NEAR(s.radius_error_p95_mm, 0.0, 1e-9);
  EXPECT_EQ(s.fn, 0);
  EXPECT_EQ(s.fp, 0);
  // 120 mm at 0.1 mm in five branches of 101..401 points; the aorta left out
  EXPECT_EQ(s.tp_reference, 1205);
  EXPECT_EQ(s.tp_extracted, 1205);
  // the LM ends where LAD and LCx begin, so it is no vessel of its own
  ASSERT_EQ(s.vessels.size(), 4u);
  EXPECT_NEAR(vessel(s, "LAD").length_mm, 50, 1e-9);
  EXPECT_NEAR(vessel(s, "LCx").length_mm, 40, 1e-9);
  EXPECT_NEAR(vessel(s, "D1").length_mm, 40, 1e-9);
  EXPECT_NEAR(vessel(s, "OM1").length_mm, 45, 1e-9);
  for (const auto& v : s.vessels) {
    EXPECT_DOUBLE_EQ(v.ov, 1.0) << v.name;
    EXPECT_DOUBLE_EQ(v.of, 1.0) << v.name;
    EXPECT_TRUE(std::isnan(v.first_fn_mm)) << v.name;
  }
}

TEST(CenterlineScores, ShiftWithinTheRadiusGivesItsDistanceAsAi) {
  // every point of either tree lies exactly 0.3 mm from the other (the trees lie in parallel planes)
  const CenterlineScores s = score_centerlines(tree(), shifted(tree(), {0, 0, 0.3}));
  EXPECT_DOUBLE_EQ(s.ov, 1.0);
  EXPECT_DOUBLE_EQ(s.of, 1.0);
  EXPECT_NEAR(s.ai_mm, 0.3, 1e-9);
  for (const auto& v : s.vessels) EXPECT_NEAR(v.ai_mm, 0.3, 1e-9) << v.name;

  // one oblique vessel of radius 1 mm, shifted 0.3 mm across it
  const Vector3d dir = Vector3d(1, 2, 3).normalized(), across = dir.unitOrthogonal();
  VesselTree one;
  one.branches.push_back(straight("RCA", -1, -1, {0, 0, 0}, 60 * dir, 1.0, 0.7));
  const CenterlineScores o = score_centerlines(one, shifted(one, 0.3 * across));
  EXPECT_DOUBLE_EQ(o.ov, 1.0);
  // a shift across the axis keeps every point's foot on the other centerline, ends included
  EXPECT_NEAR(o.ai_mm, 0.3, 1e-9);
}

TEST(CenterlineScores, ShiftBeyondTheRadiusOverlapsNothing) {
  const CenterlineScores s = score_centerlines(tree(), shifted(tree(), {0, 0, 2.5}));  // widest radius 2 mm
  EXPECT_EQ(s.ov, 0.0);
  EXPECT_EQ(s.of, 0.0);
  EXPECT_EQ(s.ot, 0.0);
  EXPECT_EQ(s.tp_reference + s.tp_extracted, 0);
  EXPECT_TRUE(std::isnan(s.ai_mm));
  for (const auto& v : s.vessels) EXPECT_NEAR(v.first_fn_mm, 0.0, 1e-9) << v.name;

  VesselTree one;
  one.branches.push_back(straight("RCA", -1, -1, {0, 0, 0}, {0, 40, 0}, 1.0));
  EXPECT_EQ(score_centerlines(one, shifted(one, {1.2, 0, 0})).ov, 0.0);
}

TEST(CenterlineScores, MissingDistalHalfOfABranch) {
  VesselTree cut = tree();
  cut.branches[4].points.resize(11);  // D1 ends at 10 of its 20 mm
  const CenterlineScores s = score_centerlines(tree(), cut);
  // reference points of D1 farther than its radius (1 mm) past the cut are missed: 9 mm;
  // every extracted point (110 mm) lies on the reference
  const double fn_mm = 10 - 1.0, extracted_mm = kTreeMm - 10;
  EXPECT_NEAR(s.ov, (extracted_mm + kTreeMm - fn_mm) / (extracted_mm + kTreeMm), 1e-3);
  EXPECT_NEAR(s.fn, fn_mm / 0.1, 1);
  EXPECT_EQ(s.fp, 0);
  // D1's vessel (LM 10 + LAD 10 + D1 20 mm) fails 31 mm from the ostium; the others are whole
  const VesselScores& d1 = vessel(s, "D1");
  EXPECT_NEAR(d1.first_fn_mm, 31.0, 0.11);
  EXPECT_NEAR(d1.of, 31.0 / 40.0, 3e-3);
  EXPECT_NEAR(d1.ov, (30 + 31.0) / (30 + 40.0), 3e-3);
  EXPECT_NEAR(s.of, (3 + 31.0 / 40.0) / 4, 1e-3);
  EXPECT_DOUBLE_EQ(vessel(s, "LAD").ov, 1.0);
  EXPECT_DOUBLE_EQ(vessel(s, "LAD").of, 1.0);
}

TEST(CenterlineScores, SpuriousBranchLowersOverlap) {
  VesselTree extra = tree();
  // 10 mm straight up out of the LAD at 30 mm: within the LAD's radius (1.5 mm) it still overlaps
  extra.branches.push_back(straight("X", 2, 30, {40, 0, 0}, {40, 0, 10}, 1.0));
  const CenterlineScores s = score_centerlines(tree(), extra);
  const double fp_mm = 10 - 1.5;
  EXPECT_NEAR(s.ov, (2 * kTreeMm + 1.5) / (2 * kTreeMm + 10), 1e-3);
  EXPECT_NEAR(s.fp, fp_mm / 0.1, 1);
  EXPECT_EQ(s.fn, 0);
  EXPECT_DOUBLE_EQ(s.of, 1.0);
  // its points are the LAD vessel's (50 mm): nearest to the LAD at 40 mm, past D1's part of it
  EXPECT_NEAR(vessel(s, "LAD").ov, (50 + 51.5) / (50 + 60.0), 2e-3);
  EXPECT_EQ(vessel(s, "LAD").fp, s.fp);
  EXPECT_DOUBLE_EQ(vessel(s, "D1").ov, 1.0);
}

TEST(CenterlineScores, ThinBranchIsLeftOutOfOt) {
  VesselTree no_om = tree();
  no_om.branches.pop_back();  // the 1.2 mm wide OM1 not found
  const CenterlineScores s = score_centerlines(tree(), no_om);
  // OM1's points beyond its radius (0.6 mm) from the LCx are missed: 19.4 of 20 mm
  EXPECT_NEAR(s.ov, (100 + kTreeMm - 19.4) / (100 + kTreeMm), 1e-3);
  EXPECT_DOUBLE_EQ(s.ot, 1.0);
  const VesselScores& om = vessel(s, "OM1");
  EXPECT_NEAR(om.ot_length_mm, 25.0, 1e-9);  // LM 10 + LCx 15: where it leaves the LCx
  EXPECT_DOUBLE_EQ(om.ot, 1.0);
  EXPECT_NEAR(om.first_fn_mm, 25.6, 0.11);
  // its vessel: 45 mm of reference (25.6 found), 25 mm of extracted points nearest to it
  EXPECT_NEAR(om.ov, (25 + 25.6) / (25 + 45.0), 3e-3);
}

TEST(CenterlineScores, OtRunsToTheLastWidePointThroughAStenosis) {
  // 40 mm of radius 1 mm narrowed to 0.5 mm at 18..22 mm, thin (0.6 mm) from 30 mm on
  VesselTree ref;
  ref.branches.push_back(straight("LAD", -1, -1, {0, 0, 0}, {40, 0, 0}, 1.0));
  auto& pts = ref.branches[0].points;
  for (int i = 18; i <= 22; ++i) pts[i].radius_m = 0.5 * kMm;
  for (int i = 30; i <= 40; ++i) pts[i].radius_m = 0.6 * kMm;
  VesselTree ext = ref;
  ext.branches[0].points.resize(21);  // stops in the stenosis, at 20 mm
  const CenterlineScores s = score_centerlines(ref, ext);
  // OT counts the reference up to 29 mm (the stenosis included) and the 20 mm extracted; of
  // those, reference points up to 20.5 mm and every extracted point are true positives
  EXPECT_NEAR(s.vessels.at(0).ot_length_mm, 29.0, 1e-9);
  EXPECT_NEAR(s.ot, (20.5 + 20) / (29 + 20.0), 3e-3);
  EXPECT_NEAR(s.ov, (20.5 + 20) / (40 + 20.0), 3e-3);
  EXPECT_NEAR(s.of, 20.5 / 40, 3e-3);
}

TEST(CenterlineScores, RadiusErrorOfScaledRadii) {
  auto scaled = [](VesselTree t) {
    for (auto& b : t.branches) {
      for (auto& p : b.points) p.radius_m *= 1.1;
    }
    return t;
  };
  VesselTree one;
  one.branches.push_back(straight("RCA", -1, -1, {0, 0, 0}, {30, 10, 5}, 1.0, 0.5));
  const CenterlineScores o = score_centerlines(one, scaled(one));
  EXPECT_NEAR(o.radius_error_mean_mm, 0.1, 1e-9);
  EXPECT_NEAR(o.radius_error_p95_mm, 0.1, 1e-9);
  EXPECT_DOUBLE_EQ(o.ov, 1.0);

  // the tree: 0.1 r weighted by length, (2*10 + 1.5*40 + 1.25*30 + 1*20 + 0.6*20) / 120 mm; the
  // widest 5 % of the length is the LM's (2 mm). Points at a junction may take the other branch.
  const CenterlineScores s = score_centerlines(tree(), scaled(tree()));
  EXPECT_NEAR(s.radius_error_mean_mm, 0.1 * 149.5 / kTreeMm, 3e-3);
  EXPECT_NEAR(s.radius_error_p95_mm, 0.2, 1e-9);
}

TEST(CenterlineScores, EmptyExtractionMissesEverything) {
  const CenterlineScores s = score_centerlines(tree(), VesselTree{});
  EXPECT_EQ(s.ov, 0.0);
  EXPECT_EQ(s.of, 0.0);
  EXPECT_EQ(s.fn, 1205);
  EXPECT_TRUE(std::isnan(s.radius_error_mean_mm));
  EXPECT_THROW(score_centerlines(tree(), tree(), {.sample_spacing_m = 0}), std::invalid_argument);
}

}  // namespace
}  // namespace pcisim::modeling
