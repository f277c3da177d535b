#include "anatomy/vessel/vessel_tree.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pcisim::anatomy {

int VesselTree::find(std::string_view name) const {
  for (size_t i = 0; i < branches.size(); ++i) {
    if (branches[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

namespace {

// squared distance from p to the segment ab (a degenerate segment is a point)
double segment_distance_sq(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len_sq = ab.squaredNorm();
  double t = len_sq > 0.0 ? (p - a).dot(ab) / len_sq : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return (a + t * ab - p).squaredNorm();
}

}  // namespace

int innermost_branch(const VesselTree& tree, const Eigen::Vector3d& p_m, double* depth_m) {
  int best = -1;
  double best_depth = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < tree.branches.size(); ++i) {
    const auto& pts = tree.branches[i].points;
    for (size_t k = 0; k < pts.size(); ++k) {
      // the segment k-1 .. k (or the lone point), its radius interpolated at the closest point
      const CenterlinePoint& a = pts[k == 0 ? 0 : k - 1];
      const CenterlinePoint& b = pts[k];
      if (k == 0 && pts.size() > 1) continue;
      const Eigen::Vector3d ab = b.position_m - a.position_m;
      const double len_sq = ab.squaredNorm();
      const double t = len_sq > 0.0 ? std::clamp((p_m - a.position_m).dot(ab) / len_sq, 0.0, 1.0) : 0.0;
      const double d = (a.position_m + t * ab - p_m).norm() - (a.radius_m + t * (b.radius_m - a.radius_m));
      if (d < best_depth) best_depth = d, best = static_cast<int>(i);
    }
  }
  if (depth_m) *depth_m = best_depth;
  return best;
}

int nearest_branch(const VesselTree& tree, const Eigen::Vector3d& p_m, double* distance_to_centerline_m) {
  int best = -1;
  double best_sq = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < tree.branches.size(); ++i) {
    const auto& pts = tree.branches[i].points;
    if (pts.size() == 1) {
      const double d = (pts[0].position_m - p_m).squaredNorm();
      if (d < best_sq) best_sq = d, best = static_cast<int>(i);
    }
    for (size_t k = 1; k < pts.size(); ++k) {
      const double d = segment_distance_sq(p_m, pts[k - 1].position_m, pts[k].position_m);
      if (d < best_sq) best_sq = d, best = static_cast<int>(i);
    }
  }
  if (distance_to_centerline_m) {
    // a NaN query point matches nothing: report infinity rather than a made-up branch distance
    *distance_to_centerline_m = best >= 0 ? std::sqrt(best_sq) : std::numeric_limits<double>::infinity();
  }
  return best;
}

double branch_length_m(const VesselBranch& branch) {
  double length = 0.0;
  for (size_t k = 1; k < branch.points.size(); ++k) {
    length += (branch.points[k].position_m - branch.points[k - 1].position_m).norm();
  }
  return length;
}

}  // namespace pcisim::anatomy
