#include "physics/guidewire/valid_region.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace pcisim::physics {

// eqs 2-4 as printed bound each world axis separately, which makes the wire stiffer along some
// directions than others. We read them in the link's own frame instead: the axial ratio within
// [alpha_min, alpha_max] (compress/stretch) and the shear angle within beta.
bool clamp_to_valid_region(const Eigen::Vector3d& sponsor, const ValidRegion& r, Eigen::Vector3d& q) {
  const Eigen::Vector3d v = q - sponsor;
  const double len = v.norm();
  if (len >= r.length_min_m && len <= r.length_max_m && len > 0.0 && v.dot(r.axis) >= r.cos_beta * len) {
    return false;  // inside the region: a chain-mail neighbour does not move
  }
  Eigen::Vector3d dir = r.axis;
  double along = len;
  if (len > 1e-15) {
    const Eigen::Vector3d d = v / len;
    const double c = std::clamp(d.dot(r.axis), -1.0, 1.0);
    if (c < r.cos_beta) {
      // outside the shear cone: project onto its nearest boundary ray
      const Eigen::Vector3d perp = d - c * r.axis;
      const double perp_len = perp.norm();
      if (perp_len > 1e-12) {
        dir = r.cos_beta * r.axis + std::sin(r.beta_rad) * (perp / perp_len);
      }
      along = std::max(v.dot(dir), 0.0);
    } else {
      dir = d;
    }
  }
  const double l = std::clamp(along, r.length_min_m, r.length_max_m);
  q = sponsor + l * dir;
  return true;
}

}  // namespace pcisim::physics
