#include "modeling/evaluation/closest_point_bvh.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace pcisim::modeling {

using Eigen::Vector3d;

namespace {
constexpr int kLeafSize = 4;
}  // namespace

AabbTree::AabbTree(const std::vector<Vector3d>& lo, const std::vector<Vector3d>& hi) {
  if (lo.empty()) return;
  order_.resize(lo.size());
  std::iota(order_.begin(), order_.end(), 0);
  nodes_.reserve(2 * lo.size() / kLeafSize + 2);
  build(lo, hi, 0, static_cast<int>(lo.size()));
}

int AabbTree::build(const std::vector<Vector3d>& lo, const std::vector<Vector3d>& hi, int first, int count) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Vector3d box_lo = Vector3d::Constant(std::numeric_limits<double>::infinity()), box_hi = -box_lo;
  Vector3d c_lo = box_lo, c_hi = box_hi;
  for (int k = first; k < first + count; ++k) {
    const int i = order_[k];
    box_lo = box_lo.cwiseMin(lo[i]);
    box_hi = box_hi.cwiseMax(hi[i]);
    const Vector3d c = 0.5 * (lo[i] + hi[i]);
    c_lo = c_lo.cwiseMin(c);
    c_hi = c_hi.cwiseMax(c);
  }
  nodes_[id].lo = box_lo;
  nodes_[id].hi = box_hi;
  if (count <= kLeafSize) {
    nodes_[id].first = first;
    nodes_[id].count = count;
    return id;
  }
  // split at the median centre along the longest extent of the centres
  int axis = 0;
  (c_hi - c_lo).maxCoeff(&axis);
  const int half = count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + first + half, order_.begin() + first + count,
                   [&](int a, int b) { return lo[a][axis] + hi[a][axis] < lo[b][axis] + hi[b][axis]; });
  const int left = build(lo, hi, first, half);
  const int right = build(lo, hi, first + half, count - half);
  nodes_[id].left = left;
  nodes_[id].right = right;
  return id;
}

std::vector<int> AabbTree::take_leaf_order() {
  std::vector<int> order = std::move(order_);
  order_.resize(order.size());
  std::iota(order_.begin(), order_.end(), 0);
  return order;
}

double closest_on_segment(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const Vector3d d = b - a;
  const double len2 = d.squaredNorm();
  if (!(len2 > 0)) return 0.0;
  return std::clamp((p - a).dot(d) / len2, 0.0, 1.0);
}

// regions tested in turn: each vertex, each edge, else the face (Ericson, Real-Time Collision
// Detection, 5.1.5)
Vector3d closest_on_triangle(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double sum = va + vb + vc;
  if (!(sum > 0)) {
    // a degenerate (zero-area) triangle: the nearest of its three edges
    Vector3d best = a;
    for (const auto& [u, v] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
      const Vector3d q = u + closest_on_segment(p, u, v) * (v - u);
      if ((q - p).squaredNorm() < (best - p).squaredNorm()) best = q;
    }
    return best;
  }
  return a + (vb / sum) * ab + (vc / sum) * ac;
}

SegmentSet::SegmentSet(std::vector<Vector3d> a, std::vector<Vector3d> b) : a_(std::move(a)), b_(std::move(b)) {
  std::vector<Vector3d> lo(a_.size()), hi(a_.size());
  for (size_t i = 0; i < a_.size(); ++i) {
    lo[i] = a_[i].cwiseMin(b_[i]);
    hi[i] = a_[i].cwiseMax(b_[i]);
  }
  tree_ = AabbTree(lo, hi);
}

SegmentSet::Hit SegmentSet::nearest(const Vector3d& p) const {
  Hit hit;
  double d2 = 0;
  hit.segment = tree_.nearest(
      p,
      [this](const Vector3d& q, int i) {
        const double t = closest_on_segment(q, a_[i], b_[i]);
        return (a_[i] + t * (b_[i] - a_[i]) - q).squaredNorm();
      },
      &d2);
  if (hit.segment >= 0) {
    hit.t = closest_on_segment(p, a_[hit.segment], b_[hit.segment]);
    hit.distance_m = std::sqrt(d2);
  }
  return hit;
}

TriangleSet::TriangleSet(const std::vector<Vector3d>& vertices, const std::vector<std::array<int, 3>>& triangles) {
  tri_.reserve(triangles.size());
  std::vector<Vector3d> lo, hi;
  lo.reserve(triangles.size());
  hi.reserve(triangles.size());
  const int n = static_cast<int>(vertices.size());
  for (size_t t = 0; t < triangles.size(); ++t) {
    for (int v : triangles[t]) {
      if (v < 0 || v >= n) {
        throw std::invalid_argument("triangle " + std::to_string(t) + " names vertex " + std::to_string(v) +
                                    " of a mesh of " + std::to_string(n));
      }
    }
    const auto& [i, j, k] = triangles[t];
    tri_.push_back({vertices[i], vertices[j], vertices[k]});
    lo.push_back(vertices[i].cwiseMin(vertices[j]).cwiseMin(vertices[k]));
    hi.push_back(vertices[i].cwiseMax(vertices[j]).cwiseMax(vertices[k]));
  }
  tree_ = AabbTree(lo, hi);
  // triangles stored in leaf order
  const std::vector<int> order = tree_.take_leaf_order();
  std::vector<std::array<Vector3d, 3>> sorted(order.size());
  for (size_t k = 0; k < order.size(); ++k) sorted[k] = tri_[order[k]];
  tri_ = std::move(sorted);
}

double TriangleSet::distance(const Vector3d& p, int* guess) const {
  double d2 = 0;
  const int i = tree_.nearest(
      p,
      [this](const Vector3d& q, int k) {
        const auto& t = tri_[k];
        return (closest_on_triangle(q, t[0], t[1], t[2]) - q).squaredNorm();
      },
      &d2, guess ? *guess : -1);
  if (guess) *guess = i;
  return std::sqrt(d2);
}

}  // namespace pcisim::modeling
