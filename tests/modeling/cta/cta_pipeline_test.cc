// The CTA pipeline end to end on small synthetic CTAs with exact truth (anatomy/phantom/phantom_cta),
// and the hard inputs it must refuse with a message naming them.
#include "modeling/cta/cta_pipeline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "anatomy/phantom/phantom_cta.h"
#include "modeling/cta/modeling_error.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

// a CTA small enough for a unit test: 0.5 mm voxels over the heart, a 60 % stenosis
anatomy::PhantomCta small_cta(uint32_t seed, bool with_coronaries = true, double stenosis = 0.6) {
  anatomy::PhantomCtaSpec spec;
  spec.seed = seed;
  spec.dims = {260, 260, 230};
  spec.spacing_mm = Vector3d(0.5, 0.5, 0.5);
  spec.with_coronaries = with_coronaries;
  spec.stenosis_fraction = stenosis;
  return anatomy::make_phantom_cta(spec);
}

// distance from p (m) to a branch's polyline (m)
double distance_to(const anatomy::VesselBranch& b, const Vector3d& p) {
  double best = 1e300;
  for (size_t i = 0; i + 1 < b.points.size(); ++i) {
    const Vector3d a = b.points[i].position_m, ab = b.points[i + 1].position_m - a;
    const double t = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-18), 0.0, 1.0);
    best = std::min(best, (a + t * ab - p).norm());
  }
  return best;
}

TEST(CtaPipeline, OneAorticSeedGivesTheNamedTreeOnTheTruth) {
  const anatomy::PhantomCta cta = small_cta(2);
  const CtaModel m = build_cta_model(cta.ct, {cta.aortic_seed_mm}, CtaPipelineOptions{});
  const anatomy::VesselTree& tree = m.model.vessels;
  ASSERT_GE(tree.branches.size(), 4u);
  EXPECT_EQ(tree.branches[0].name, "aorta");
  for (const char* name : {"LM", "LAD", "LCx", "RCA"}) {
    const int mine = tree.find(name), truth = cta.truth.find(name);
    ASSERT_GE(mine, 0) << name << " not found";
    ASSERT_GE(truth, 0);
    // every model point of the vessel lies on the true vessel: within its true radius of the centerline
    double sum_mm = 0, worst_mm = 0;
    int counted = 0;
    const auto& aorta = cta.truth.branches[cta.truth.find("aorta")];
    for (const auto& p : tree.branches[mine].points) {
      // points inside the aorta (the piece from its centre to the ostium) are not on a coronary,
      // and within 4 mm of its wall the model's line is the vessel's own carried back straight
      // through the ostium's funnel (off by up to ~2.5 mm there: docs/modeling.md)
      if (distance_to(aorta, p.position_m) < aorta.points.front().radius_m + 4e-3) continue;
      ++counted;
      const double d_mm = distance_to(cta.truth.branches[truth], p.position_m) * 1e3;
      sum_mm += d_mm;
      worst_mm = std::max(worst_mm, d_mm);
    }
    ASSERT_GE(counted, 5) << name;
    const double mean_mm = sum_mm / counted;
    std::printf("%s: %zu points, %.1f mm long (truth %.1f), mean distance to truth %.2f mm, worst %.2f mm\n", name,
                tree.branches[mine].points.size(), anatomy::branch_length_m(tree.branches[mine]) * 1e3,
                anatomy::branch_length_m(cta.truth.branches[truth]) * 1e3, mean_mm, worst_mm);
    EXPECT_LT(mean_mm, 0.6) << name;  // one voxel
  }
  // a lumen for the SDF: one closed tube per branch
  EXPECT_GT(m.model.lumen.triangles.size(), 1000u);
}

// Known failure, issue #13 open: the tree stops at the phantom's stenosis (LAD at ~27 mm of 126) and
// loses thin distal segments (LCx 31 of 82 mm, RCA 75 of 134 mm on this phantom). Enabled when the
// gap bridging past stenoses lands.
TEST(CtaPipeline, DISABLED_EachMajorVesselIsFollowedPastHalfItsLength) {
  const anatomy::PhantomCta cta = small_cta(2);
  const CtaModel m = build_cta_model(cta.ct, {cta.aortic_seed_mm}, CtaPipelineOptions{});
  for (const char* name : {"LAD", "LCx", "RCA"}) {
    const int mine = m.model.vessels.find(name), truth = cta.truth.find(name);
    ASSERT_GE(mine, 0) << name;
    EXPECT_GT(anatomy::branch_length_m(m.model.vessels.branches[mine]),
              0.5 * anatomy::branch_length_m(cta.truth.branches[truth]))
        << name;
  }
}

TEST(CtaPipeline, ASeedOutsideTheVolumeIsNamedWithTheExtent) {
  const anatomy::PhantomCta cta = small_cta(3);
  try {
    build_cta_model(cta.ct, {cta.aortic_seed_mm + Vector3d(0, 0, 500)}, CtaPipelineOptions{});
    FAIL() << "no error";
  } catch (const ModelingError& e) {
    EXPECT_NE(std::string(e.what()).find("outside the CT"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("seed 1"), std::string::npos) << e.what();
  }
}

TEST(CtaPipeline, ASeedNotInContrastIsNamedWithItsHu) {
  const anatomy::PhantomCta cta = small_cta(3);
  // 6 mm outward from the middle of the LAD: epicardial or pericardial fat
  const auto& lad = cta.truth.branches[cta.truth.find("LAD")];
  const Vector3d mid = lad.points[lad.points.size() / 2].position_m * 1e3;
  const Vector3d off = mid + 6.0 * (mid - cta.facts.heart_center_mm).normalized();
  try {
    build_cta_model(cta.ct, {cta.aortic_seed_mm, off}, CtaPipelineOptions{});
    FAIL() << "no error";
  } catch (const ModelingError& e) {
    EXPECT_NE(std::string(e.what()).find("seed 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not in contrast"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("HU"), std::string::npos) << e.what();
  }
}

TEST(CtaPipeline, ACtaWithoutCoronariesIsAnErrorNotATreeOfNoise) {
  const anatomy::PhantomCta cta = small_cta(4, /*with_coronaries=*/false);
  try {
    const CtaModel m = build_cta_model(cta.ct, {cta.aortic_seed_mm}, CtaPipelineOptions{});
    FAIL() << "a tree of " << m.model.vessels.branches.size() << " branches";
  } catch (const ModelingError& e) {
    EXPECT_NE(std::string(e.what()).find("no coronary artery"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pcisim::modeling
