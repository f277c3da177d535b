#pragma once
// What the wire asks of the vessel: signed distance to the lumen wall and the outward normal.
// An interface so the same contact code runs on the SDF grid and on analytic test tubes.
#include <Eigen/Core>

namespace pcisim::physics {

struct WallSample {
  double distance_m = 0.0;                            // < 0 inside the lumen
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();  // unit, points out of the lumen
};

class LumenQuery {
 public:
  virtual ~LumenQuery() = default;
  // finite for every finite point; allocates nothing
  virtual WallSample sample(const Eigen::Vector3d& p_m) const = 0;
};

}  // namespace pcisim::physics
