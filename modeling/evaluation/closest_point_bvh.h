#pragma once
// Nearest-point queries against many segments or triangles (the accuracy measures compare
// centerlines and lumen meshes of ~100k triangles): a bounding-volume hierarchy of axis-aligned
// boxes, split at the median of the longest axis, searched nearest box first.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <limits>
#include <vector>

namespace pcisim::modeling {

// a hierarchy of boxes; the caller supplies the exact distance to a primitive
class AabbTree {
 public:
  AabbTree() = default;
  // builds over one box (lo, hi) per primitive
  AabbTree(const std::vector<Eigen::Vector3d>& lo, const std::vector<Eigen::Vector3d>& hi);

  bool empty() const { return nodes_.empty(); }

  // the primitive i minimising distance2(p, i) (a squared distance, never below the squared
  // distance from p to that primitive's box), or -1 when empty; *best_d2 receives its value.
  // A guess (a primitive likely near, such as the previous query's) prunes from the start.
  template <class Distance2>
  int nearest(const Eigen::Vector3d& p, Distance2&& distance2, double* best_d2, int guess = -1) const;

  // the primitives in the order the leaves hold them; after this call the tree numbers them
  // 0, 1, ... in that order (the owner stores them so: neighbours in space then share cache lines)
  std::vector<int> take_leaf_order();

  // calls visit(i) for every primitive whose box lies within sqrt(max_d2) of p
  template <class Visit>
  void visit_near(const Eigen::Vector3d& p, double max_d2, Visit&& visit) const;

 private:
  struct Node {
    Eigen::Vector3d lo, hi;
    int first = 0, count = 0;  // a leaf's primitives in order_ (count > 0)
    int left = -1, right = -1;
  };
  int build(const std::vector<Eigen::Vector3d>& lo, const std::vector<Eigen::Vector3d>& hi, int first, int count);
  static double box_distance2(const Node& n, const Eigen::Vector3d& p) {
    return (n.lo - p).cwiseMax(p - n.hi).cwiseMax(0.0).squaredNorm();
  }
  static constexpr double kTieRatio = 1 - 1e-9;  // squared distances this close count as equal
  std::vector<Node> nodes_;
  std::vector<int> order_;
};

template <class Distance2>
int AabbTree::nearest(const Eigen::Vector3d& p, Distance2&& distance2, double* best_d2, int guess) const {
  double best = std::numeric_limits<double>::infinity();
  int best_i = -1;
  if (guess >= 0 && guess < static_cast<int>(order_.size())) best = distance2(p, guess), best_i = guess;
  if (!nodes_.empty()) {
    // the depth of a median split stays below 64 for any size that fits in memory
    std::array<int, 128> stack;
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      // a box only as near as the best (to rounding) cannot hold a nearer primitive: a fan of
      // slivers whose boxes all meet at its centre is skipped, not searched whole
      if (box_distance2(n, p) >= best * kTieRatio) continue;
      if (n.count > 0) {
        for (int k = n.first; k < n.first + n.count; ++k) {
          const double d2 = distance2(p, order_[k]);
          if (d2 < best) best = d2, best_i = order_[k];
        }
        continue;
      }
      // push the farther child first so the nearer one is searched first
      const double dl = box_distance2(nodes_[n.left], p), dr = box_distance2(nodes_[n.right], p);
      const int near = dl <= dr ? n.left : n.right, far = dl <= dr ? n.right : n.left;
      if (std::max(dl, dr) < best * kTieRatio) stack[top++] = far;
      if (std::min(dl, dr) < best * kTieRatio) stack[top++] = near;
    }
  }
  *best_d2 = best;
  return best_i;
}

template <class Visit>
void AabbTree::visit_near(const Eigen::Vector3d& p, double max_d2, Visit&& visit) const {
  if (nodes_.empty()) return;
  std::array<int, 128> stack;
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (box_distance2(n, p) > max_d2) continue;
    if (n.count > 0) {
      for (int k = n.first; k < n.first + n.count; ++k) visit(order_[k]);
      continue;
    }
    stack[top++] = n.left;
    stack[top++] = n.right;
  }
}

// the parameter t in [0, 1] of the point a + t (b - a) nearest to p
double closest_on_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b);

// the point of triangle (a, b, c) nearest to p (Voronoi regions of its vertices, edges and face)
Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c);

// segments (a[i], b[i]) under a hierarchy
class SegmentSet {
 public:
  struct Hit {
    int segment = -1;  // -1 when the set is empty
    double t = 0;      // along the segment, 0 at a, 1 at b
    double distance_m = std::numeric_limits<double>::infinity();
  };
  SegmentSet(std::vector<Eigen::Vector3d> a, std::vector<Eigen::Vector3d> b);
  // the nearest point of any segment
  Hit nearest(const Eigen::Vector3d& p) const;
  // calls visit(Hit) for every segment within max_distance_m of p, with its nearest point
  template <class Visit>
  void visit_within(const Eigen::Vector3d& p, double max_distance_m, Visit&& visit) const {
    tree_.visit_near(p, max_distance_m * max_distance_m, [&](int i) {
      Hit h{i, closest_on_segment(p, a_[i], b_[i]), 0.0};
      h.distance_m = (a_[i] + h.t * (b_[i] - a_[i]) - p).norm();
      if (h.distance_m <= max_distance_m) visit(h);
    });
  }

 private:
  std::vector<Eigen::Vector3d> a_, b_;
  AabbTree tree_;
};

// triangles of a mesh under a hierarchy
class TriangleSet {
 public:
  // throws std::invalid_argument for a vertex index out of range
  TriangleSet(const std::vector<Eigen::Vector3d>& vertices, const std::vector<std::array<int, 3>>& triangles);
  // the distance from p to the nearest triangle, infinite when there is none. *guess, when given,
  // names a triangle likely near (the last query's, for nearby points) and receives the nearest.
  double distance(const Eigen::Vector3d& p, int* guess = nullptr) const;

 private:
  std::vector<std::array<Eigen::Vector3d, 3>> tri_;
  AabbTree tree_;
};

}  // namespace pcisim::modeling
