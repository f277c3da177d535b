#pragma once
// The valid region of a chain-mail neighbour (eqs 2-4) and the nearest point inside it.
#include <Eigen/Core>

namespace pcisim::physics {

struct ValidRegion {
  Eigen::Vector3d axis;       // unit rest direction of the link, seen from the sponsor
  double length_min_m = 0.0;  // alpha_min * rest
  double length_max_m = 0.0;  // alpha_max * rest
  double beta_rad = 0.0;      // shear: largest angle away from axis
  double cos_beta = 1.0;
};

// where neighbour q must move when its sponsor sits at `sponsor`: q itself when already valid,
// otherwise the nearest point of the region (rotate towards the axis, then clamp the length).
// Coincident or reversed points land on the axis. Returns true when q moved.
bool clamp_to_valid_region(const Eigen::Vector3d& sponsor, const ValidRegion& region, Eigen::Vector3d& q);

}  // namespace pcisim::physics
