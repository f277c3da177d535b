#include "xray/overlay/wire_overlay.h"

#include <limits>

#include "xray/overlay/tube_overlay.h"

namespace pcisim::xray {

void add_wire(const DetectorGeometry& g, const std::vector<Eigen::Vector3d>& wire_mm, const WireSpec& wire,
              Image* image) {
  // a chain of cylinders: cones of equal radii
  for (size_t k = 0; k + 1 < wire_mm.size(); ++k) {
    add_cone_segment(g, wire_mm[k], wire_mm[k + 1], wire.radius_mm, wire.radius_mm, wire.mu_per_mm, image);
  }
}

void project_polyline(const DetectorGeometry& g, const std::vector<Eigen::Vector3d>& points_mm,
                      std::vector<Eigen::Vector2d>* pixels) {
  pixels->resize(points_mm.size());
  for (size_t k = 0; k < points_mm.size(); ++k) {
    if (!g.project(points_mm[k], &(*pixels)[k])) {
      (*pixels)[k].setConstant(std::numeric_limits<double>::quiet_NaN());
    }
  }
}

}  // namespace pcisim::xray
