#include "xray/geometry/c_arm.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

namespace pcisim::xray {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

TEST(CArm, IsocentreProjectsToTheDetectorCentre) {
  CArmSpec spec;
  spec.width = 640;
  spec.height = 480;
  for (double a : {-90.0, -30.0, 0.0, 45.0, 120.0}) {
    for (double b : {-40.0, 0.0, 25.0}) {
      CArmPose pose{a, b, Vector3d(12, -30, 55)};
      const DetectorGeometry g = c_arm_geometry(spec, pose);
      EXPECT_EQ(validate(g), "");
      Vector2d cr;
      ASSERT_TRUE(g.project(pose.isocenter_mm, &cr));
      EXPECT_NEAR(cr.x(), 319.5, 1e-9) << a << " " << b;
      EXPECT_NEAR(cr.y(), 239.5, 1e-9) << a << " " << b;
      EXPECT_NEAR((g.source_mm - pose.isocenter_mm).norm(), spec.source_to_axis_mm, 1e-9);
      EXPECT_NEAR((g.center_mm - g.source_mm).norm(), spec.source_to_image_mm, 1e-9);
    }
  }
}

TEST(CArm, ApViewLooksFromBehindWithHeadUpAndLeftOnTheRight) {
  const DetectorGeometry g = c_arm_geometry(CArmSpec{}, CArmPose{});
  // the source under the table (posterior, +y), the detector over the chest
  EXPECT_GT(g.source_mm.y(), 0);
  EXPECT_LT(g.center_mm.y(), 0);
  Vector2d head, left;
  ASSERT_TRUE(g.project(Vector3d(0, 0, 50), &head));
  ASSERT_TRUE(g.project(Vector3d(50, 0, 0), &left));
  EXPECT_LT(head.y(), 255.5);  // superior is up (smaller row)
  EXPECT_GT(left.x(), 255.5);  // patient's left on the image's right
}

TEST(CArm, Lao90IsALateralViewAlongPatientX) {
  const DetectorGeometry g = c_arm_geometry(CArmSpec{}, CArmPose{90, 0, Vector3d::Zero()});
  const Vector3d ray = (g.center_mm - g.source_mm).normalized();
  EXPECT_TRUE(ray.isApprox(Vector3d::UnitX(), 1e-12)) << ray.transpose();
  EXPECT_GT(g.center_mm.x(), 0);  // detector on the patient's left
  // RAO 90 looks the other way
  const DetectorGeometry r = c_arm_geometry(CArmSpec{}, CArmPose{-90, 0, Vector3d::Zero()});
  EXPECT_TRUE((r.center_mm - r.source_mm).normalized().isApprox(-Vector3d::UnitX(), 1e-12));
  // a point on the patient's x axis stays on the central ray
  Vector2d cr;
  ASSERT_TRUE(g.project(Vector3d(80, 0, 0), &cr));
  EXPECT_NEAR(cr.x(), 255.5, 1e-9);
  EXPECT_NEAR(cr.y(), 255.5, 1e-9);
}

TEST(CArm, CranialTiltsTheDetectorTowardTheHead) {
  const DetectorGeometry g = c_arm_geometry(CArmSpec{}, CArmPose{0, 30, Vector3d::Zero()});
  const Vector3d ray = (g.center_mm - g.source_mm).normalized();
  EXPECT_NEAR(ray.z(), 0.5, 1e-12);  // sin 30
  EXPECT_GT(g.center_mm.z(), 0);
  EXPECT_LT(g.source_mm.z(), 0);
  const DetectorGeometry c = c_arm_geometry(CArmSpec{}, CArmPose{0, -30, Vector3d::Zero()});
  EXPECT_LT(c.center_mm.z(), 0);  // caudal: detector toward the feet
  // image rows stay perpendicular to the beam and still run toward the feet
  EXPECT_NEAR(g.v.dot(ray), 0, 1e-12);
  EXPECT_LT(g.v.z(), 0);
}

TEST(CArm, AnglesRoundTrip) {
  for (double a = -170; a <= 180; a += 17.5) {
    for (double b = -85; b <= 85; b += 12.5) {
      const Vector2d back = c_arm_angles(c_arm_beam_direction(a, b));
      EXPECT_NEAR(back.x(), a, 1e-9);
      EXPECT_NEAR(back.y(), b, 1e-9);
    }
  }
}

TEST(DetectorGeometry, PixelCentresProjectBackToThemselves) {
  const DetectorGeometry g = c_arm_geometry(CArmSpec{}, CArmPose{-25, 20, Vector3d(3, 4, 5)});
  for (double c : {0.0, 17.25, 255.5, 511.0}) {
    for (double r : {0.0, 100.0, 511.0}) {
      const Vector3d p = g.pixel_center_mm(c, r);
      // any point on the ray from the source to the pixel lands on that pixel
      const Vector3d mid = g.source_mm + 0.37 * (p - g.source_mm);
      Vector2d cr;
      ASSERT_TRUE(g.project(mid, &cr));
      EXPECT_NEAR(cr.x(), c, 1e-9);
      EXPECT_NEAR(cr.y(), r, 1e-9);
    }
  }
  Vector2d cr;
  EXPECT_FALSE(g.project(g.source_mm - (g.center_mm - g.source_mm), &cr));  // behind the source
}

TEST(DetectorGeometry, ValidateNamesTheProblem) {
  DetectorGeometry g;
  EXPECT_EQ(validate(g), "");
  g.v = g.u;
  EXPECT_EQ(validate(g), "u and v must be perpendicular");
  g = DetectorGeometry{};
  g.pixel_mm = 0;
  EXPECT_EQ(validate(g), "pixel_mm = 0 is not positive");
  g = DetectorGeometry{};
  g.source_mm = g.center_mm + g.u;
  EXPECT_EQ(validate(g), "the source lies in the detector plane");
}

}  // namespace
}  // namespace pcisim::xray
