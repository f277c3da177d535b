#pragma once
// Where an ultrasound frame's pixels lie (docs/ultrasound.md "Pixel -> world"), for the programs
// that store or show frames: the image is a rectangle in the probe's plane, x along `lateral`,
// y along `beam`, both mm from `origin_mm`. Pixel (c, r) has its centre at
// origin_mm + (x0_mm + (c + 0.5) pixel_x_mm) lateral + (y0_mm + (r + 0.5) pixel_y_mm) beam.
// Linear: the array's width by the depth. Curvilinear: the fan's bounding rectangle, into which
// the fan was scan-converted (black outside the fan).
#include <cmath>
#include <numbers>

#include "pcisim_lcm/us_frame_t.hpp"

namespace pcisim::protocol {

struct UsImagePlane {
  double x0_mm = 0, y0_mm = 0;            // the image's top-left corner (not a pixel centre)
  double width_mm = 0, height_mm = 0;     // its extent along lateral and beam
  double pixel_x_mm = 0, pixel_y_mm = 0;  // one pixel's size along lateral and beam
};

// for a frame that passed is_well_formed (positive sizes)
inline UsImagePlane us_image_plane(const pcisim_lcm::us_frame_t& m) {
  UsImagePlane p;
  if (m.geometry == pcisim_lcm::us_frame_t::GEOMETRY_LINEAR) {
    p.width_mm = m.width_mm;
    p.y0_mm = 0;
    p.height_mm = m.depth_mm;
  } else {
    // the fan's widest point is its deepest edge; its shallowest, the face's ends
    const double half_rad = 0.5 * m.fan_angle_deg * std::numbers::pi / 180.0, rc = m.radius_of_curvature_mm;
    p.width_mm = 2.0 * (rc + m.depth_mm) * std::sin(half_rad);
    p.y0_mm = rc * (std::cos(half_rad) - 1.0);
    p.height_mm = m.depth_mm - p.y0_mm;
  }
  p.x0_mm = -0.5 * p.width_mm;
  p.pixel_x_mm = p.width_mm / m.width;
  p.pixel_y_mm = p.height_mm / m.height;
  return p;
}

}  // namespace pcisim::protocol
