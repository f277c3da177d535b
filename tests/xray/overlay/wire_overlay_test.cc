#include "xray/overlay/wire_overlay.h"

#include <gtest/gtest.h>

#include <cmath>

#include "xray/geometry/c_arm.h"

namespace pcisim::xray {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

// AP C-arm with an odd detector, so the central pixel's ray is the central ray
DetectorGeometry ap(int size, double pixel_mm) {
  CArmSpec c;
  c.width = c.height = size;
  c.pixel_mm = pixel_mm;
  return c_arm_geometry(c, CArmPose{});
}

TEST(WireOverlay, CentralRayAcrossAStraightWireSeesItsDiameter) {
  const DetectorGeometry g = ap(9, 0.05);
  Image img;
  img.resize(9, 9);
  const WireSpec wire;
  // along x through the isocentre, perpendicular to the central ray (which runs along -y)
  add_wire(g, {Vector3d(-20, 0, 0), Vector3d(0.5, 0, 0), Vector3d(20, 0, 0)}, wire, &img);
  EXPECT_NEAR(img.at(4, 4), wire.mu_per_mm * 2 * wire.radius_mm, 1e-6);
  // rows beyond the wire's magnified shadow (radius 0.18 mm x 1.47 ~ 0.26 mm ~ 5 pixels of
  // 0.05 mm) see nothing; the central row is covered along its whole width
  for (int c = 0; c < 9; ++c) EXPECT_GT(img.at(c, 4), 0.f) << c;
  Image far;
  far.resize(9, 9);
  add_wire(g, {Vector3d(-20, 0, 5), Vector3d(20, 0, 5)}, wire, &far);  // 5 mm above: off the detector
  for (float v : far.pixels) EXPECT_EQ(v, 0.f);
}

TEST(WireOverlay, ChordFollowsTheCircleAcrossTheShadow) {
  // a wire along x; rows of pixels sample the circle's chord 2 sqrt(R^2 - h^2), where h is the
  // ray's distance from the axis at the wire (the beam is nearly parallel there)
  const DetectorGeometry g = ap(41, 0.01);
  Image img;
  img.resize(41, 41);
  WireSpec wire;
  wire.radius_mm = 0.1;
  wire.mu_per_mm = 1.0;
  add_wire(g, {Vector3d(-10, 0, 0), Vector3d(10, 0, 0)}, wire, &img);
  const double sad = (g.source_mm).norm(), sid = (g.center_mm - g.source_mm).norm();
  for (int r = 0; r < 41; ++r) {
    const double h = std::abs((r - 20) * 0.01 * sad / sid);  // detector offset back at the wire
    const double want = h < wire.radius_mm ? 2 * std::sqrt(wire.radius_mm * wire.radius_mm - h * h) : 0.0;
    EXPECT_NEAR(img.at(20, r), want, 2e-4) << r;
  }
}

TEST(WireOverlay, ProjectedPolylineLandsWhereTheRaysGo) {
  const DetectorGeometry g = c_arm_geometry(CArmSpec{}, CArmPose{30, 20, Vector3d::Zero()});
  const std::vector<Vector3d> pts = {Vector3d::Zero(), Vector3d(10, -5, 20), g.source_mm - (g.center_mm - g.source_mm)};
  std::vector<Vector2d> px;
  project_polyline(g, pts, &px);
  ASSERT_EQ(px.size(), 3u);
  EXPECT_NEAR(px[0].x(), 255.5, 1e-9);
  EXPECT_NEAR(px[0].y(), 255.5, 1e-9);
  // the pixel centre found for point 1 lies on the ray from the source through it
  const Vector3d on_detector = g.pixel_center_mm(px[1].x(), px[1].y());
  const Vector3d ray = (on_detector - g.source_mm).normalized();
  const Vector3d to_point = pts[1] - g.source_mm;
  EXPECT_LT((to_point - ray * ray.dot(to_point)).norm(), 1e-9);
  EXPECT_TRUE(std::isnan(px[2].x()));  // behind the source
}

}  // namespace
}  // namespace pcisim::xray
