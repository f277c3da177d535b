#include "xray/geometry/detector_geometry.h"

#include <Eigen/Geometry>
#include <cmath>
#include <fmt/format.h>

namespace pcisim::xray {

Eigen::Vector3d DetectorGeometry::normal() const {
  Eigen::Vector3d n = u.cross(v).normalized();
  if (n.dot(center_mm - source_mm) < 0) n = -n;
  return n;
}

bool DetectorGeometry::project(const Eigen::Vector3d& p_mm, Eigen::Vector2d* cr) const {
  const Eigen::Vector3d n = normal();
  const double depth = n.dot(p_mm - source_mm);  // distance along the normal from the source
  if (!(depth > 0)) return false;
  const double sid = n.dot(center_mm - source_mm);
  const Eigen::Vector3d hit = source_mm + (sid / depth) * (p_mm - source_mm);
  const Eigen::Vector3d d = hit - center_mm;
  cr->x() = d.dot(u) / pixel_mm + 0.5 * (width - 1);
  cr->y() = d.dot(v) / pixel_mm + 0.5 * (height - 1);
  return true;
}

std::string validate(const DetectorGeometry& g) {
  if (!g.source_mm.allFinite() || !g.center_mm.allFinite() || !g.u.allFinite() || !g.v.allFinite()) {
    return "non-finite source, center, u or v";
  }
  if (std::abs(g.u.norm() - 1) > 1e-6 || std::abs(g.v.norm() - 1) > 1e-6) return "u and v must be unit vectors";
  if (std::abs(g.u.dot(g.v)) > 1e-6) return "u and v must be perpendicular";
  if (!(g.pixel_mm > 0) || !std::isfinite(g.pixel_mm)) return fmt::format("pixel_mm = {} is not positive", g.pixel_mm);
  if (g.width < 1 || g.height < 1) return fmt::format("size {}x{} is not positive", g.width, g.height);
  if (std::abs(g.u.cross(g.v).dot(g.center_mm - g.source_mm)) < 1e-6) return "the source lies in the detector plane";
  return {};
}

DetectorGeometry coarse_detector(const DetectorGeometry& g, int stride) {
  const int s = stride;
  DetectorGeometry c = g;
  c.width = (g.width + s - 1) / s;
  c.height = (g.height + s - 1) / s;
  c.pixel_mm = g.pixel_mm * s;
  // the coarse centre: where its pixel ((W_c - 1) / 2, (H_c - 1) / 2) falls on g
  const double dc = 0.5 * (c.width - 1) * s + 0.5 * (s - 1) - 0.5 * (g.width - 1);
  const double dr = 0.5 * (c.height - 1) * s + 0.5 * (s - 1) - 0.5 * (g.height - 1);
  c.center_mm = g.center_mm + (dc * g.pixel_mm) * g.u + (dr * g.pixel_mm) * g.v;
  return c;
}

DetectorGeometry detector_rows(const DetectorGeometry& g, int first_row, int rows) {
  DetectorGeometry b = g;
  b.height = rows;
  b.center_mm = g.pixel_center_mm(0.5 * (g.width - 1), first_row + 0.5 * (rows - 1));
  return b;
}

}  // namespace pcisim::xray
