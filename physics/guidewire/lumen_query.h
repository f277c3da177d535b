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

// how the lumen moves over the current step (effect vessel_motion): the displacement of the
// wall off the rest frame, where LumenQuery describes it, at a rest-frame point and a fraction
// a of the step (0: where the last step left it, 1: where this step takes it)
class LumenMotion {
 public:
  virtual ~LumenMotion() = default;
  // finite for every finite point; allocates nothing
  virtual Eigen::Vector3d displacement_m(const Eigen::Vector3d& rest_p_m, double a) const = 0;
  // whether the motion reaches a rest-frame point at all (the vessel skin's blend: a point beyond
  // every centerline's blend radius stands still by default, not because its vessel does)
  virtual bool carries(const Eigen::Vector3d& rest_p_m) const { return rest_p_m.allFinite(); }
};

}  // namespace pcisim::physics
