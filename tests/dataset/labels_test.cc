// The labels' geometry against independent arithmetic: the 3x4 matrix against the detector's own
// ray-plane projection, keypoints along a straight wire, and the COCO RLE decoded back.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
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

// the box of the pixels equal to id, row by row: [first column, first row, columns spanned, rows
// spanned], the COCO box of whole pixels (pixel (c, r) covers [c, c + 1) x [r, r + 1))
std::array<int, 4> box_of(const std::vector<uint8_t>& ids, int w, int h, uint8_t id) {
  int c0 = w, r0 = h, c1 = -1, r1 = -1;
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c)
      if (ids[r * w + c] == id) c0 = std::min(c0, c), r0 = std::min(r0, r), c1 = std::max(c1, c), r1 = std::max(r1, r);
  return {c0, r0, c1 - c0 + 1, r1 - r0 + 1};
}

TEST(Coco, EachBranchsAnnotationDecodesToItsPixels) {
  const int w = 9, h = 6;
  std::vector<uint8_t> ids(w * h, 0);
  for (int r = 0; r < h; ++r) ids[r * w + 2] = 1;  // a vertical vessel, branch index 0: 6 pixels
  for (int c = 4; c < 8; ++c) ids[4 * w + c] = 4;  // a horizontal one, branch index 3: 4 pixels
  ids[w * h - 1] = 4;                              // and its lone last pixel: 5 in all
  // no visible keypoint: no wire annotation
  const std::vector<Eigen::Vector3d> hidden(3, Eigen::Vector3d(4, 2, 0));
  EXPECT_EQ(coco_frame_annotations(hidden, ids, w, h, {"LM", "LAD", "LCx", "D1"}).size(), 2u);
  // a wire in the image's lower left: one keypoint outside (v = 0), the last on the bottom row
  // near the left edge so that its box is cut at two edges
  const std::vector<Eigen::Vector3d> keys = {{-3, 1, 0}, {1.25, 2.5, 2}, {3, 3.75, 2}, {0.25, 5, 2}};
  const auto anns = coco_frame_annotations(keys, ids, w, h, {"LM", "LAD", "LCx", "D1"});
  ASSERT_EQ(anns.size(), 3u);
  const auto& wire = anns[0];
  EXPECT_EQ(wire["category_id"], 1);
  EXPECT_EQ(wire["num_keypoints"], 3);
  // COCO keypoints: pixel centre + 0.5, the hidden one (0, 0, 0)
  EXPECT_EQ(wire["keypoints"], nlohmann::json({0, 0, 0, 1.75, 3.0, 2, 3.5, 4.25, 2, 0.75, 5.5, 2}));
  // the visible keypoints span x [0.75, 3.5] and y [3.0, 5.5]; grown by a pixel each way and cut
  // at the image's left and bottom edges (x >= 0, y <= 6): [0.0, 2.0] to [4.5, 6.0]
  EXPECT_EQ(wire["bbox"], nlohmann::json({0.0, 2.0, 4.5, 4.0}));
  EXPECT_EQ(wire["area"], 18.0);
  // then the branches in id order
  EXPECT_EQ(anns[1]["branch"], "LM");
  EXPECT_EQ(anns[2]["branch"], "D1");
  for (size_t i = 1; i < anns.size(); ++i) {
    const auto& a = anns[i];
    const uint8_t id = i == 1 ? 1 : 4;
    EXPECT_EQ(a["category_id"], 2);
    std::vector<uint8_t> back(w * h, 0);
    int64_t at = 0;
    bool in = false;
    for (const auto& n : a["segmentation"]["counts"]) {
      for (int64_t k = 0; k < n.get<int64_t>(); ++k, ++at)
        if (in) back[(at % h) * w + at / h] = id;
      in = !in;
    }
    EXPECT_EQ(at, w * h);
    for (int p = 0; p < w * h; ++p) EXPECT_EQ(back[p] != 0, ids[p] == id) << a["branch"] << " pixel " << p;
    // LM: column 2, every row; D1: columns 4..7 of row 4 and the last pixel (8, 5)
    EXPECT_EQ(a["area"], id == 1 ? 6 : 5) << a["branch"];
    EXPECT_EQ(a["area"], std::count(back.begin(), back.end(), id)) << a["branch"];
    // the box around the decoded mask's pixels, and the synthetic truth's
    const std::array<int, 4> want = id == 1 ? std::array<int, 4>{2, 0, 1, 6} : std::array<int, 4>{4, 4, 5, 2};
    const auto box = a["bbox"].get<std::array<int, 4>>();
    EXPECT_EQ(box, box_of(back, w, h, id)) << a["branch"];
    EXPECT_EQ(box, want) << a["branch"];
  }
}

}  // namespace
}  // namespace pcisim::dataset
