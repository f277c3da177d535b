#include "physics/guidewire/tube_lumen.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace pcisim::physics {

namespace {
constexpr int kLeafSegments = 4;
constexpr int kMaxTreeDepth = 64;  // a median split halves a node: depth ~ log2(segments / 4)
}  // namespace

TubeLumen::TubeLumen(const anatomy::VesselTree& tree, double bin_m, double band_m) : bin_m_(bin_m) {
  for (const auto& branch : tree.branches) {
    const auto& pts = branch.points;
    for (size_t k = 0; k + 1 < pts.size(); ++k) {
      segments_.push_back({pts[k].position_m, pts[k + 1].position_m, pts[k].radius_m, pts[k + 1].radius_m});
    }
    if (pts.size() == 1) {
      segments_.push_back({pts[0].position_m, pts[0].position_m, pts[0].radius_m, pts[0].radius_m});
    }
  }
  if (segments_.empty()) return;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& s : segments_) {
    const double r = std::max(s.ra, s.rb) + band_m;
    lo = lo.cwiseMin(s.a.cwiseMin(s.b) - Eigen::Vector3d::Constant(r));
    hi = hi.cwiseMax(s.a.cwiseMax(s.b) + Eigen::Vector3d::Constant(r));
  }
  origin_ = lo;
  for (int k = 0; k < 3; ++k) dims_[k] = std::max(1, static_cast<int>(std::ceil((hi[k] - lo[k]) / bin_m_)));
  const size_t bins = static_cast<size_t>(dims_.x()) * dims_.y() * dims_.z();
  std::vector<std::vector<int>> lists(bins);
  for (size_t si = 0; si < segments_.size(); ++si) {
    const auto& s = segments_[si];
    const double r = std::max(s.ra, s.rb) + band_m;
    const Eigen::Vector3d a = s.a.cwiseMin(s.b) - Eigen::Vector3d::Constant(r) - origin_;
    const Eigen::Vector3d b = s.a.cwiseMax(s.b) + Eigen::Vector3d::Constant(r) - origin_;
    Eigen::Vector3i i0, i1;
    for (int k = 0; k < 3; ++k) {
      i0[k] = std::clamp(static_cast<int>(std::floor(a[k] / bin_m_)), 0, dims_[k] - 1);
      i1[k] = std::clamp(static_cast<int>(std::floor(b[k] / bin_m_)), 0, dims_[k] - 1);
    }
    for (int z = i0.z(); z <= i1.z(); ++z)
      for (int y = i0.y(); y <= i1.y(); ++y)
        for (int x = i0.x(); x <= i1.x(); ++x)
          lists[(static_cast<size_t>(z) * dims_.y() + y) * dims_.x() + x].push_back(static_cast<int>(si));
  }
  bin_start_.resize(bins + 1, 0);
  for (size_t b = 0; b < bins; ++b) bin_start_[b + 1] = bin_start_[b] + static_cast<int>(lists[b].size());
  bin_items_.reserve(bin_start_.back());
  for (const auto& l : lists) bin_items_.insert(bin_items_.end(), l.begin(), l.end());

  order_.resize(segments_.size());
  for (size_t i = 0; i < order_.size(); ++i) order_[i] = static_cast<int>(i);
  tree_.reserve(2 * segments_.size() / kLeafSegments + 2);
  build_tree(0, static_cast<int>(segments_.size()));
}

// one node over order_[first, first + count): split at the median of the segments' midpoints
// along the box's longest side until a leaf holds kLeafSegments
int TubeLumen::build_tree(int first, int count) {
  const int at = static_cast<int>(tree_.size());
  tree_.push_back({});
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int i = first; i < first + count; ++i) {
    const Segment& s = segments_[order_[i]];
    const double r = std::max(s.ra, s.rb);
    lo = lo.cwiseMin(s.a.cwiseMin(s.b) - Eigen::Vector3d::Constant(r));
    hi = hi.cwiseMax(s.a.cwiseMax(s.b) + Eigen::Vector3d::Constant(r));
  }
  tree_[at].lo = lo;
  tree_[at].hi = hi;
  tree_[at].first = first;
  tree_[at].count = count;
  if (count <= kLeafSegments) return at;
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const int half = count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + first + half, order_.begin() + first + count,
                   [&](int u, int v) {
                     return segments_[u].a[axis] + segments_[u].b[axis] < segments_[v].a[axis] + segments_[v].b[axis];
                   });
  const int left = build_tree(first, half);
  const int right = build_tree(first + half, count - half);
  tree_[at].left = left;
  tree_[at].right = right;
  return at;
}

void TubeLumen::consider(const Segment& s, const Eigen::Vector3d& p, WallSample& best) const {
  const Eigen::Vector3d ab = s.b - s.a;
  const double len_sq = ab.squaredNorm();
  const double t = len_sq > 0.0 ? std::clamp((p - s.a).dot(ab) / len_sq, 0.0, 1.0) : 0.0;
  const Eigen::Vector3d off = p - (s.a + t * ab);
  const double dist = off.norm();
  const double sd = dist - (s.ra + t * (s.rb - s.ra));
  if (sd >= best.distance_m) return;
  best.distance_m = sd;
  if (dist > 1e-12) {
    best.normal = off / dist;
  } else {
    // on the centerline: any direction across the segment is outward
    const Eigen::Vector3d axis = len_sq > 0.0 ? Eigen::Vector3d(ab / std::sqrt(len_sq)) : Eigen::Vector3d::UnitZ();
    best.normal = axis.unitOrthogonal();
  }
}

// the nearest capsule below the tree's nodes, nearer child first; a node is skipped when the
// query is farther from its box than the best distance so far (its capsules lie inside the box,
// so none of them is nearer). The box distance bounds a capsule's signed distance from below only
// outside it; the walk runs for queries in a bin of no tube, which lie outside every capsule by
// at least the band, so it holds there
void TubeLumen::nearest_by_tree(const Eigen::Vector3d& p, WallSample& best) const {
  int stack[kMaxTreeDepth + 1];
  int top = 0;
  stack[top++] = 0;
  auto box_distance = [&](int n) {
    const Eigen::Vector3d out = (tree_[n].lo - p).cwiseMax(p - tree_[n].hi).cwiseMax(0.0);
    return out.norm();
  };
  while (top > 0) {
    const BoxNode& n = tree_[stack[--top]];
    if (box_distance(static_cast<int>(&n - tree_.data())) >= best.distance_m) continue;
    if (n.left < 0) {
      for (int i = n.first; i < n.first + n.count; ++i) consider(segments_[order_[i]], p, best);
      continue;
    }
    // the nearer child is popped first
    const bool left_first = box_distance(n.left) <= box_distance(n.right);
    stack[top++] = left_first ? n.right : n.left;
    stack[top++] = left_first ? n.left : n.right;
  }
}

WallSample TubeLumen::sample(const Eigen::Vector3d& p) const {
  // union of capsules: the smallest signed distance among the query's bin's tubes
  WallSample best;
  best.distance_m = std::numeric_limits<double>::infinity();
  bool binned = false;
  if (!bin_start_.empty()) {
    const Eigen::Vector3d q = (p - origin_) / bin_m_;
    if ((q.array() >= 0.0).all() && q.x() < dims_.x() && q.y() < dims_.y() && q.z() < dims_.z()) {
      const size_t b = (static_cast<size_t>(q.z()) * dims_.y() + static_cast<size_t>(q.y())) * dims_.x() +
                       static_cast<size_t>(q.x());
      for (int k = bin_start_[b]; k < bin_start_[b + 1]; ++k) consider(segments_[bin_items_[k]], p, best);
      binned = bin_start_[b + 1] > bin_start_[b];
    }
  }
  // far from every tube: the nearest of all of them
  if (!binned && !tree_.empty() && p.allFinite()) nearest_by_tree(p, best);
  if (!std::isfinite(best.distance_m)) {
    best.distance_m = 1.0;  // empty tree or non-finite query: everything is wall
    best.normal = Eigen::Vector3d::UnitX();
  }
  return best;
}

}  // namespace pcisim::physics
