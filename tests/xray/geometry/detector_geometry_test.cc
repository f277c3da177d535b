// The coarse and banded detectors a C-arm move's quick projection uses: their pixels are where
// the whole detector's are, by the pixel-centre formula of detector_geometry.h.
#include "xray/geometry/detector_geometry.h"

#include <gtest/gtest.h>

namespace pcisim::xray {
namespace {

DetectorGeometry tilted() {
  DetectorGeometry g;
  g.u = Eigen::Vector3d(1, 1, 0).normalized();
  g.v = Eigen::Vector3d(0, 0, -1);
  g.center_mm = Eigen::Vector3d(3, -350, 7);
  g.width = 10;
  g.height = 7;  // not a multiple of the strides below
  return g;
}

TEST(DetectorGeometry, ACoarsePixelIsCentredOnItsBlock) {
  const DetectorGeometry g = tilted();
  for (int s : {1, 2, 3, 4}) {
    const DetectorGeometry c = coarse_detector(g, s);
    EXPECT_EQ(c.width, (10 + s - 1) / s) << s;
    EXPECT_EQ(c.height, (7 + s - 1) / s) << s;
    EXPECT_DOUBLE_EQ(c.pixel_mm, s * g.pixel_mm);
    for (int r = 0; r < c.height; ++r)
      for (int col = 0; col < c.width; ++col) {
        // coarse (C, R) on fine (s C + (s - 1) / 2, s R + (s - 1) / 2)
        const Eigen::Vector3d fine = g.pixel_center_mm(s * col + 0.5 * (s - 1), s * r + 0.5 * (s - 1));
        EXPECT_LT((c.pixel_center_mm(col, r) - fine).norm(), 1e-9) << s << " " << col << " " << r;
      }
  }
}

TEST(DetectorGeometry, ABandOfRowsHasTheWholeDetectorsPixels) {
  const DetectorGeometry g = tilted();
  for (int first : {0, 2, 5})
    for (int rows : {1, 2}) {
      const DetectorGeometry b = detector_rows(g, first, rows);
      EXPECT_EQ(b.width, g.width);
      EXPECT_EQ(b.height, rows);
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < g.width; ++c)
          EXPECT_LT((b.pixel_center_mm(c, r) - g.pixel_center_mm(c, first + r)).norm(), 1e-9) << first << " " << r;
    }
}

}  // namespace
}  // namespace pcisim::xray
