#pragma once
// The guide catheter's centerline: where the proximal wire lives (not simulated freely).
// The wire leaves it at the last point (the LM ostium) along the last segment's direction.
#include <Eigen/Core>
#include <vector>

namespace pcisim::physics {

class CatheterPath {
 public:
  // points from proximal to the exit; throws std::invalid_argument when fewer than two distinct
  // points or a non-finite point are given
  explicit CatheterPath(std::vector<Eigen::Vector3d> points_m);

  // the point `back_m` (>= 0) behind the exit along the path; past the proximal end the path
  // continues straight. Allocates nothing.
  Eigen::Vector3d point_behind_exit(double back_m) const;
  const Eigen::Vector3d& exit_m() const { return points_.back(); }
  const Eigen::Vector3d& exit_direction() const { return exit_dir_; }
  // the way the catheter curves at its exit (unit, across the exit direction): the bend plane a
  // pre-bent tip resting in it lies in, i.e. both wire models' tip direction at rotation 0; any
  // direction across the exit when the last 20 mm are straight
  Eigen::Vector3d exit_curl() const;
  double length_m() const { return cumulative_.back(); }

 private:
  std::vector<Eigen::Vector3d> points_;
  std::vector<double> cumulative_;  // arc length from the proximal point
  Eigen::Vector3d exit_dir_ = Eigen::Vector3d::UnitZ();
};

}  // namespace pcisim::physics
