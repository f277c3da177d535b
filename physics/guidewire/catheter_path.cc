#include "physics/guidewire/catheter_path.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <stdexcept>

namespace pcisim::physics {

CatheterPath::CatheterPath(std::vector<Eigen::Vector3d> points_m) {
  // drop repeated points so every segment has a direction
  for (const auto& p : points_m) {
    if (!p.allFinite()) throw std::invalid_argument("catheter path: non-finite point");
    if (points_.empty() || (p - points_.back()).norm() > 1e-9) points_.push_back(p);
  }
  if (points_.size() < 2) throw std::invalid_argument("catheter path: needs two distinct points");
  cumulative_.resize(points_.size());
  cumulative_[0] = 0.0;
  for (size_t k = 1; k < points_.size(); ++k) {
    cumulative_[k] = cumulative_[k - 1] + (points_[k] - points_[k - 1]).norm();
  }
  exit_dir_ = (points_.back() - points_[points_.size() - 2]).normalized();
}

Eigen::Vector3d CatheterPath::point_behind_exit(double back_m) const {
  const double s = cumulative_.back() - std::max(back_m, 0.0);
  if (s <= 0.0) {
    const Eigen::Vector3d d = (points_[1] - points_[0]).normalized();
    return points_[0] + s * d;  // straight on beyond the proximal end
  }
  // binary search for the segment holding arc length s
  const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), s);
  const size_t k = std::min<size_t>(std::max<ptrdiff_t>(it - cumulative_.begin(), 1), points_.size() - 1);
  const double seg = cumulative_[k] - cumulative_[k - 1];
  const double t = seg > 0.0 ? (s - cumulative_[k - 1]) / seg : 0.0;
  return points_[k - 1] + std::clamp(t, 0.0, 1.0) * (points_[k] - points_[k - 1]);
}

Eigen::Vector3d CatheterPath::exit_curl() const {
  const Eigen::Vector3d& t = exit_dir_;
  const Eigen::Vector3d back = point_behind_exit(std::min(0.02, 0.5 * length_m()));
  const Eigen::Vector3d d = exit_m() - back;
  const Eigen::Vector3d chord = d.norm() > 1e-12 ? Eigen::Vector3d(d.normalized()) : t;
  const Eigen::Vector3d curl = (t - chord) - (t - chord).dot(t) * t;
  return curl.norm() > 1e-6 ? Eigen::Vector3d(curl.normalized()) : t.unitOrthogonal();
}

}  // namespace pcisim::physics
