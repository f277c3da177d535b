#include "anatomy/phantom/tube_phantoms.h"

#include <cmath>
#include <numbers>

namespace pcisim::anatomy {

VesselTree tube_through(const std::vector<Eigen::Vector3d>& centerline_m, double lumen_radius_m) {
  VesselTree tree;
  VesselBranch b;
  b.name = "tube";
  b.parent = -1;
  for (const Eigen::Vector3d& p : centerline_m) b.points.push_back({p, lumen_radius_m});
  tree.branches.push_back(b);
  return tree;
}

VesselTree bent_tube_phantom() {
  std::vector<Eigen::Vector3d> c;
  for (double z = 0.0; z <= 0.04 + 1e-9; z += 1e-3) c.push_back({0.0, 0.0, z});
  for (int k = 1; k <= 24; ++k) {
    const double a = 0.5 * std::numbers::pi * k / 24.0;
    c.push_back({0.015 * (1.0 - std::cos(a)), 0.0, 0.04 + 0.015 * std::sin(a)});
  }
  for (double x = 0.016; x <= 0.075 + 1e-9; x += 1e-3) c.push_back({x, 0.0, 0.055});
  return tube_through(c, 1.5e-3);
}

}  // namespace pcisim::anatomy
