#pragma once
// What the beating-heart tests check after every step: finite, inside bounds, springs not torn.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "physics/heart/beating_heart.h"

namespace pcisim::physics::testing {

struct HeartHealth {
  bool finite = true;
  double max_from_rest_m = 0;  // any particle's distance from its rest position
  double max_free_from_rest_m = 0;
  double max_strain = 0;  // |length / rest - 1| over the distance constraints
  double free_kinetic_j = 0;

  void merge(const HeartHealth& o) {
    finite = finite && o.finite;
    max_from_rest_m = std::max(max_from_rest_m, o.max_from_rest_m);
    max_free_from_rest_m = std::max(max_free_from_rest_m, o.max_free_from_rest_m);
    max_strain = std::max(max_strain, o.max_strain);
    free_kinetic_j = std::max(free_kinetic_j, o.free_kinetic_j);
  }
};

inline HeartHealth health(const BeatingHeart& h) {
  HeartHealth out;
  const Eigen::Matrix3Xd& x = h.positions_m();
  const Eigen::Matrix3Xd& rest = h.rest_positions_m();
  out.finite = x.allFinite();
  for (int i = 0; i < x.cols(); ++i)
    out.max_from_rest_m = std::max(out.max_from_rest_m, (x.col(i) - rest.col(i)).norm());
  const auto& p = h.system().particles();
  for (int i : h.free_particles()) {
    out.max_free_from_rest_m = std::max(out.max_free_from_rest_m, (x.col(i) - rest.col(i)).norm());
    out.free_kinetic_j += 0.5 * p.mass_kg[i] * p.velocity_m_per_s.col(i).squaredNorm();
  }
  for (const auto& c : h.system().distance_constraints())
    out.max_strain = std::max(out.max_strain, std::abs((x.col(c.i) - x.col(c.j)).norm() / c.rest_m - 1.0));
  if (!std::isfinite(out.max_strain) || !std::isfinite(out.free_kinetic_j)) out.finite = false;
  return out;
}

}  // namespace pcisim::physics::testing
