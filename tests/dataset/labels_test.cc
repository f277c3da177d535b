// The labels' geometry against independent arithmetic: the 3x4 matrix against the detector's own
// ray-plane projection, keypoints along a straight wire, and the COCO RLE decoded back.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "dataset/sample/coco.h"
#include "dataset/sample/frame_labels.h"
#include "xray/geometry/c_arm.h"

namespace pcisim::dataset {
namespace {

xray::DetectorGeometry oblique_geometry() {
  xray::CArmSpec spec;
  spec.width = 300;
  spec.height = 200;
  spec.pixel_mm = 0.7;
  xray::CArmPose pose;
  pose.primary_deg = 35;
  pose.secondary_deg = -20;
  pose.isocenter_mm = Eigen::Vector3d(10, -30, 150);
  return xray::c_arm_geometry(spec, pose);
}

TEST(FrameLabels, TheProjectionMatrixMapsPointsWhereTheDetectorsRaysMeetIt) {
  const xray::DetectorGeometry g = oblique_geometry();
  const Eigen::Matrix<double, 3, 4> p = projection_matrix(g);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d x = g.source_mm + (g.center_mm - g.source_mm) * (0.3 + 0.01 * i) +
                              Eigen::Vector3d(3.0 * (i % 7) - 9, 2.0 * (i % 5) - 4, 1.5 * (i % 3));
    Eigen::Vector2d cr;
    ASSERT_TRUE(g.project(x, &cr));
    const Eigen::Vector3d h = p * x.homogeneous();
    EXPECT_GT(h.z(), 0);
    EXPECT_NEAR(h.x() / h.z(), cr.x(), 1e-9);
    EXPECT_NEAR(h.y() / h.z(), cr.y(), 1e-9);
    // and the pixel's centre is on the ray: the documented pixel convention
    const Eigen::Vector3d on_detector = g.pixel_center_mm(cr.x(), cr.y());
    const Eigen::Vector3d ray = (x - g.source_mm).normalized();
    EXPECT_LT((on_detector - g.source_mm).normalized().cross(ray).norm(), 1e-9);
  }
}

TEST(FrameLabels, KeypointsAreEvenAlongTheDistalSpanWithTheTipLast) {
  const xray::DetectorGeometry g = oblique_geometry();
  // a straight wire 200 mm long through the isocentre, nodes every 10 mm
  std::vector<Eigen::Vector3d> wire;
  const Eigen::Vector3d dir = g.u;
  for (int k = 0; k <= 20; ++k) wire.push_back(Eigen::Vector3d(10, -30, 150) + (k * 10.0 - 150) * dir);
  const auto keys = wire_keypoints(g, wire, 5, 40);
  ASSERT_EQ(keys.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    Eigen::Vector2d expect;
    ASSERT_TRUE(g.project(wire.back() - (40.0 - 10.0 * i) * dir, &expect));
    EXPECT_NEAR(keys[i].x(), expect.x(), 1e-9);
    EXPECT_NEAR(keys[i].y(), expect.y(), 1e-9);
  }
  // the tip is 50 mm past the isocentre along u: inside a 210 mm wide image, v = 2
  EXPECT_EQ(keys.back().z(), 2);
  // a span longer than the wire starts at its first node
  const auto all = wire_keypoints(g, wire, 3, 1000);
  Eigen::Vector2d first;
  g.project(wire.front(), &first);
  EXPECT_NEAR(all.front().x(), first.x(), 1e-9);
}

TEST(Coco, RleDecodesBackToTheRegion) {
  const int w = 7, h = 5;
  std::vector<uint8_t> labels(w * h, 0);
  for (int r = 1; r < 4; ++r)
    for (int c = 2; c < 6; ++c) labels[r * w + c] = 3;
  labels[0] = 3;  // a lone pixel at the first one: the first run is of length 0
  int64_t area = 0;
  std::array<int, 4> box{};
  const nlohmann::json rle = coco_rle(labels, w, h, 3, &area, &box);
  EXPECT_EQ(area, 13);
  EXPECT_EQ(box, (std::array<int, 4>{0, 0, 6, 4}));
  EXPECT_EQ(rle["size"], nlohmann::json({h, w}));
  EXPECT_EQ(rle["counts"][0], 0);
  // decode: runs alternate out / in, column-major
  std::vector<uint8_t> back(w * h, 0);
  int64_t at = 0;
  bool in = false;
  for (const auto& n : rle["counts"]) {
    for (int64_t k = 0; k < n.get<int64_t>(); ++k, ++at)
      if (in) back[(at % h) * w + at / h] = 3;
    in = !in;
  }
  EXPECT_EQ(at, w * h);
  EXPECT_EQ(back, labels);
}

TEST(Coco, EachBranchsAnnotationDecodesToItsPixels) {
  const int w = 9, h = 6;
  std::vector<uint8_t> ids(w * h, 0);
  for (int r = 0; r < h; ++r) ids[r * w + 2] = 1;  // a vertical vessel, branch index 0
  for (int c = 3; c < 8; ++c) ids[4 * w + c] = 4;  // a horizontal one, branch index 3
  ids[w * h - 1] = 4;                              // and its lone last pixel
  const auto anns = coco_frame_annotations({}, ids, w, h, {"LM", "LAD", "LCx", "D1"});
  ASSERT_EQ(anns.size(), 2u);  // no visible keypoint: no wire annotation
  for (const auto& a : anns) {
    const int id = a["branch"] == "LM" ? 1 : 4;
    EXPECT_EQ(a["category_id"], 2);
    std::vector<uint8_t> back(w * h, 0);
    int64_t at = 0;
    bool in = false;
    for (const auto& n : a["segmentation"]["counts"]) {
      for (int64_t k = 0; k < n.get<int64_t>(); ++k, ++at)
        if (in) back[(at % h) * w + at / h] = static_cast<uint8_t>(id);
      in = !in;
    }
    EXPECT_EQ(at, w * h);
    for (int p = 0; p < w * h; ++p) EXPECT_EQ(back[p] != 0, ids[p] == id) << a["branch"] << " pixel " << p;
    EXPECT_EQ(a["area"], id == 1 ? 6 : 6);
  }
}

}  // namespace
}  // namespace pcisim::dataset
