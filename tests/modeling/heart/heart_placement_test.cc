// Stage (g), the heart's pose: the phantom CTAs are posed (rotation, scale, offset) from the
// template's own tree, so their truth trees carry the exact pose the placement must find.
#include "modeling/heart/heart_placement.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

#include "anatomy/phantom/phantom_cta.h"

namespace pcisim::modeling {
namespace {

double angle_deg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180.0 / 3.14159265358979;
}

anatomy::PhantomCta posed(uint32_t seed) {
  anatomy::PhantomCtaSpec spec;
  spec.seed = seed;
  spec.dims = {40, 40, 40};  // the truth tree is what matters; a tiny volume keeps it fast
  spec.spacing_mm = Eigen::Vector3d::Constant(5.0);
  spec.blur_sigma_mm = 0;
  return anatomy::make_phantom_cta(spec);
}

TEST(HeartPlacement, FindsThePoseOfThePhantomItsTemplateWasBuiltAround) {
  // phantom 1's tree is the template's, posed: only the added tortuosity differs
  const anatomy::PhantomCta cta = posed(1);
  const HeartPlacement h = place_template_heart(cta.truth, HeartPlacementOptions{});
  const double rot_err = angle_deg(h.pose.rotation, cta.facts.heart_rotation);
  const double offset_mm = (h.pose.translation_m * 1e3 - cta.facts.heart_center_mm).norm();
  std::printf("rotation error %.2f deg (pose %.1f deg), scale %.3f (truth %.3f), offset %.2f mm, rms %.2f mm\n",
              rot_err, cta.facts.heart_rotation_deg.norm(), h.pose.scale, cta.facts.heart_scale, offset_mm, h.rms_mm);
  EXPECT_LT(rot_err, 2.0);
  EXPECT_NEAR(h.pose.scale, cta.facts.heart_scale, 0.02);
  EXPECT_LT(offset_mm, 2.0);
}

TEST(HeartPlacement, OtherPhantomsLandTheHeartNearTheirPose) {
  // other seeds grow a different tree: the pose is that of the best-fitting template, close
  for (uint32_t seed : {2u, 3u, 5u}) {
    const anatomy::PhantomCta cta = posed(seed);
    const HeartPlacement h = place_template_heart(cta.truth, HeartPlacementOptions{});
    const double rot_err = angle_deg(h.pose.rotation, cta.facts.heart_rotation);
    const double offset_mm = (h.pose.translation_m * 1e3 - cta.facts.heart_center_mm).norm();
    std::printf("seed %u: rotation error %.2f deg, scale %.3f (truth %.3f), offset %.2f mm, rms %.2f mm\n", seed,
                rot_err, h.pose.scale, cta.facts.heart_scale, offset_mm, h.rms_mm);
    EXPECT_LT(rot_err, 10.0) << seed;
    EXPECT_NEAR(h.pose.scale, cta.facts.heart_scale, 0.1) << seed;
    EXPECT_LT(offset_mm, 8.0) << seed;
  }
}

TEST(HeartPlacement, RefusesATreeTooSmallToPlaceAHeartUnder) {
  anatomy::VesselTree t;
  t.branches.push_back({"LM", -1, -1, {{Eigen::Vector3d::Zero(), 1e-3}, {Eigen::Vector3d(0.002, 0, 0), 1e-3}}});
  EXPECT_THROW(place_template_heart(t, HeartPlacementOptions{}), std::invalid_argument);
}

}  // namespace
}  // namespace pcisim::modeling
