#include "xray/geometry/c_arm.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace pcisim::xray {

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
}

Eigen::Vector3d c_arm_beam_direction(double primary_deg, double secondary_deg) {
  const double a = primary_deg * kDeg, b = secondary_deg * kDeg;
  return Eigen::Vector3d(std::sin(a) * std::cos(b), -std::cos(a) * std::cos(b), std::sin(b));
}

Eigen::Vector2d c_arm_angles(const Eigen::Vector3d& d) {
  const Eigen::Vector3d n = d.normalized();
  const double secondary = std::asin(std::clamp(n.z(), -1.0, 1.0));
  const double horizontal = std::hypot(n.x(), n.y());
  const double primary = horizontal < 1e-12 ? 0.0 : std::atan2(n.x(), -n.y());
  return Eigen::Vector2d(primary / kDeg, secondary / kDeg);
}

DetectorGeometry c_arm_geometry(const CArmSpec& spec, const CArmPose& pose) {
  const double a = pose.primary_deg * kDeg;
  const Eigen::Vector3d d = c_arm_beam_direction(pose.primary_deg, pose.secondary_deg);
  DetectorGeometry g;
  g.source_mm = pose.isocenter_mm - spec.source_to_axis_mm * d;
  g.center_mm = g.source_mm + spec.source_to_image_mm * d;
  g.u = Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
  g.v = g.u.cross(d).normalized();
  g.pixel_mm = spec.pixel_mm;
  g.width = spec.width;
  g.height = spec.height;
  return g;
}

}  // namespace pcisim::xray
