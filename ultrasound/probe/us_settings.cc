#include "ultrasound/probe/us_settings.h"

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace pcisim::ultrasound {
namespace {

void check(double v, double lo, double hi, const char* field, bool lo_open = false) {
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
  if (!ok)
    throw std::invalid_argument(
        fmt::format("ultrasound settings: {} = {} is outside {}{}, {}]", field, v, lo_open ? "(" : "[", lo, hi));
}

}  // namespace

void validate(const UsSettings& s) {
  if (s.geometry == ProbeGeometry::kLinear) {
    check(s.width_mm, 0.0, 200.0, "width_mm", true);
  } else {
    check(s.fan_angle_deg, 0.0, 150.0, "fan_angle_deg", true);
    check(s.radius_of_curvature_mm, 0.0, 200.0, "radius_of_curvature_mm", true);
  }
  check(s.depth_mm, 0.0, kUsMaxDepthMm, "depth_mm", true);
  check(s.width_px, 8, 2048, "width_px");
  check(s.threads, 1, kUsMaxThreads, "threads");
  check(s.height_px, 8, 4096, "height_px");
  check(s.gain_db, -kUsMaxGainDb, kUsMaxGainDb, "gain_db");
  check(s.tgc_db_per_cm, -20.0, 40.0, "tgc_db_per_cm");
  check(s.frequency_mhz, 1.0, 20.0, "frequency_mhz");
  check(s.attenuation_db_per_cm_mhz, 0.0, 5.0, "attenuation_db_per_cm_mhz");
  check(s.dynamic_range_db, 10.0, 120.0, "dynamic_range_db");
  check(s.speckle_cell_mm, 0.02, 2.0, "speckle_cell_mm");
  check(s.bandwidth, kUsBandwidthMin, kUsBandwidthMax, "bandwidth");
  check(s.f_number, kUsFNumberMin, kUsFNumberMax, "f_number");
  check(s.focus_mm, 0.0, kUsMaxDepthMm, "focus_mm", true);
  check(s.specular_exponent, 0.0, kUsSpecularExponentMax, "specular_exponent");
}

void validate(const ProbePose& p) {
  const double b = p.beam.norm(), l = p.lateral.norm();
  if (!p.origin_mm.allFinite()) throw std::invalid_argument("ultrasound probe: origin_mm is not finite");
  if (!(std::isfinite(b) && b > 0.0)) throw std::invalid_argument("ultrasound probe: beam is zero or not finite");
  if (!(std::isfinite(l) && l > 0.0)) throw std::invalid_argument("ultrasound probe: lateral is zero or not finite");
  if ((p.beam / b).cross(p.lateral / l).norm() < 1e-6)
    throw std::invalid_argument("ultrasound probe: lateral is parallel to beam");
}

Eigen::Vector3d pixel_to_world(const UsSettings& s, const ProbePose& p, double col, double row) {
  const Eigen::Vector3d b = p.beam.normalized();
  const Eigen::Vector3d l = (p.lateral - p.lateral.dot(b) * b).normalized();
  const double t = (col + 0.5) / s.width_px - 0.5;
  const double d = (row + 0.5) / s.height_px * s.depth_mm;
  if (s.geometry == ProbeGeometry::kLinear) return p.origin_mm + t * s.width_mm * l + d * b;
  const double theta = t * s.fan_angle_deg * std::numbers::pi / 180.0;
  const double rc = s.radius_of_curvature_mm;
  return p.origin_mm - rc * b + (rc + d) * (std::cos(theta) * b + std::sin(theta) * l);
}

namespace {

// the display point in the probe's plane (x lateral, y along the beam), mm
Eigen::Vector2d display_plane_mm(const UsSettings& s, double col, double row) {
  if (s.geometry == ProbeGeometry::kLinear)
    return {((col + 0.5) / s.width_px - 0.5) * s.width_mm, (row + 0.5) / s.height_px * s.depth_mm};
  const double half = 0.5 * s.fan_angle_deg * std::numbers::pi / 180.0, rc = s.radius_of_curvature_mm;
  const double x_max = (rc + s.depth_mm) * std::sin(half), y0 = rc * (std::cos(half) - 1.0);
  return {-x_max + (col + 0.5) / s.width_px * 2.0 * x_max, y0 + (row + 0.5) / s.height_px * (s.depth_mm - y0)};
}

}  // namespace

Eigen::Vector3d display_pixel_to_world(const UsSettings& s, const ProbePose& p, double col, double row) {
  const Eigen::Vector3d b = p.beam.normalized();
  const Eigen::Vector3d l = (p.lateral - p.lateral.dot(b) * b).normalized();
  const Eigen::Vector2d q = display_plane_mm(s, col, row);
  return p.origin_mm + q.x() * l + q.y() * b;
}

bool display_to_beam(const UsSettings& s, double col, double row, double* beam_col, double* beam_row) {
  const Eigen::Vector2d q = display_plane_mm(s, col, row);
  if (s.geometry == ProbeGeometry::kLinear) {
    *beam_col = col;
    *beam_row = row;
    return true;
  }
  const double rc = s.radius_of_curvature_mm, fan = s.fan_angle_deg * std::numbers::pi / 180.0;
  const double theta = std::atan2(q.x(), q.y() + rc), d = std::hypot(q.x(), q.y() + rc) - rc;
  *beam_col = (theta / fan + 0.5) * s.width_px - 0.5;
  *beam_row = d / s.depth_mm * s.height_px - 0.5;
  return std::abs(theta) <= 0.5 * fan && d >= 0.0 && d <= s.depth_mm;
}

}  // namespace pcisim::ultrasound
