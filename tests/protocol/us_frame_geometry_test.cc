#include "protocol/us_frame_geometry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <numbers>
#include <utility>

namespace pcisim::protocol {
namespace {

pcisim_lcm::us_frame_t frame(int8_t geometry) {
  pcisim_lcm::us_frame_t m{};
  m.width = 256;
  m.height = 128;
  m.geometry = geometry;
  m.depth_mm = 60;
  m.width_mm = 40;
  m.fan_angle_deg = 60;
  m.radius_of_curvature_mm = 40;
  return m;
}

// the pixel's centre in the probe's plane (x lateral, y beam), mm
std::pair<double, double> centre(const UsImagePlane& p, double c, double r) {
  return {p.x0_mm + (c + 0.5) * p.pixel_x_mm, p.y0_mm + (r + 0.5) * p.pixel_y_mm};
}

// us_frame_t.lcm's formula: (c + 0.5 - width/2) (width_mm/width) lateral + (r + 0.5) (depth_mm/height) beam
TEST(UsImagePlane, LinearIsTheArrayWidthByTheDepth) {
  const auto m = frame(pcisim_lcm::us_frame_t::GEOMETRY_LINEAR);
  const UsImagePlane p = us_image_plane(m);
  EXPECT_DOUBLE_EQ(p.width_mm, 40.0);
  EXPECT_DOUBLE_EQ(p.height_mm, 60.0);
  for (const auto& [c, r] : std::initializer_list<std::pair<int, int>>{{0, 0}, {255, 127}, {100, 31}}) {
    const auto [x, y] = centre(p, c, r);
    EXPECT_NEAR(x, (c + 0.5 - 128.0) * (40.0 / 256), 1e-12);
    EXPECT_NEAR(y, (r + 0.5) * (60.0 / 128), 1e-12);
  }
}

// the fan's extreme points lie on the rectangle's edges: its deep corners on the sides, the ends of
// the face on the top, the deepest point of the axis on the bottom
TEST(UsImagePlane, CurvilinearIsTheFansBoundingRectangle) {
  const auto m = frame(pcisim_lcm::us_frame_t::GEOMETRY_CURVILINEAR);
  const UsImagePlane p = us_image_plane(m);
  const double half = 30.0 * std::numbers::pi / 180.0, rc = 40.0, depth = 60.0;
  // a point on the ray at angle theta, d below the face; apex at origin - rc beam
  auto fan = [&](double theta, double d) {
    return std::pair{(rc + d) * std::sin(theta), (rc + d) * std::cos(theta) - rc};
  };
  EXPECT_NEAR(fan(half, depth).first, p.x0_mm + p.width_mm, 1e-12) << "deep right corner on the right edge";
  EXPECT_NEAR(fan(-half, depth).first, p.x0_mm, 1e-12) << "deep left corner on the left edge";
  EXPECT_NEAR(fan(half, 0).second, p.y0_mm, 1e-12) << "the face's end on the top edge";
  EXPECT_NEAR(fan(0, depth).second, p.y0_mm + p.height_mm, 1e-12) << "the axis's deepest point on the bottom";
  EXPECT_LT(p.y0_mm, 0.0) << "the face's ends lie above its centre";
  EXPECT_DOUBLE_EQ(p.pixel_x_mm, p.width_mm / 256);
  EXPECT_DOUBLE_EQ(p.pixel_y_mm, p.height_mm / 128);
  // the middle column's centre is half a pixel beside the axis (an even width)
  EXPECT_NEAR(centre(p, 128, 0).first, 0.5 * p.pixel_x_mm, 1e-12);
}

}  // namespace
}  // namespace pcisim::protocol
