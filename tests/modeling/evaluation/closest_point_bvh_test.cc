// The hierarchy's nearest points against brute force over every primitive, on random triangles
// and segments (many of them thin or degenerate), from points near and far.
#include "modeling/evaluation/closest_point_bvh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <utility>

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

TEST(ClosestPointBvh, TrianglesMatchBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  auto rand3 = [&] { return Vector3d(u(rng), u(rng), u(rng)); };
  std::vector<Vector3d> v;
  std::vector<std::array<int, 3>> t;
  for (int i = 0; i < 2000; ++i) {
    const Vector3d c = rand3();
    const int k = static_cast<int>(v.size());
    v.push_back(c + 0.05 * rand3());
    v.push_back(c + 0.05 * rand3());
    // every tenth collinear (no area), every tenth a point
    v.push_back(i % 10 == 0 ? 0.5 * (v[k] + v[k + 1]) : i % 10 == 1 ? v[k] : c + 0.05 * rand3());
    t.push_back({k, k + 1, k + 2});
  }
  const TriangleSet set(v, t);
  int guess = -1;
  for (int q = 0; q < 500; ++q) {
    const Vector3d p = (q % 2 ? 1.0 : 3.0) * rand3();
    double brute = std::numeric_limits<double>::infinity();
    for (const auto& [a, b, c] : t) brute = std::min(brute, (closest_on_triangle(p, v[a], v[b], v[c]) - p).norm());
    EXPECT_NEAR(set.distance(p), brute, 1e-12);
    EXPECT_NEAR(set.distance(p, &guess), brute, 1e-12);  // a stale guess changes nothing
  }
}

TEST(ClosestPointBvh, TriangleRegions) {
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(closest_on_triangle({0.2, 0.2, 5}, a, b, c).isApprox(Vector3d(0.2, 0.2, 0)));  // face
  EXPECT_TRUE(closest_on_triangle({-1, -1, 0}, a, b, c).isApprox(a));                        // vertex
  EXPECT_TRUE(closest_on_triangle({1, 1, 0}, a, b, c).isApprox(Vector3d(0.5, 0.5, 0)));      // edge bc
  EXPECT_TRUE(closest_on_triangle({0.5, -2, 1}, a, b, c).isApprox(Vector3d(0.5, 0, 0)));     // edge ab
  // a triangle of no area: the nearest of its edges
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 200; ++i) {
    const Vector3d p(u(rng), u(rng), u(rng)), e(u(rng), u(rng), u(rng)), f = e + Vector3d(u(rng), u(rng), u(rng));
    const Vector3d g = i % 2 ? e : e + u(rng) * (f - e);
    double edges = std::numeric_limits<double>::infinity();
    for (const auto& [x, y] : {std::pair{e, f}, std::pair{f, g}, std::pair{g, e}}) {
      edges = std::min(edges, (x + closest_on_segment(p, x, y) * (y - x) - p).norm());
    }
    EXPECT_NEAR((closest_on_triangle(p, e, f, g) - p).norm(), edges, 1e-9);
  }
}

TEST(ClosestPointBvh, SegmentsMatchBruteForceAndListTies) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  auto rand3 = [&] { return Vector3d(u(rng), u(rng), u(rng)); };
  std::vector<Vector3d> a, b;
  for (int i = 0; i < 3000; ++i) {
    a.push_back(rand3());
    b.push_back(i % 7 == 0 ? a.back() : a.back() + 0.1 * rand3());  // some of no length
  }
  const SegmentSet set(a, b);
  for (int q = 0; q < 500; ++q) {
    const Vector3d p = 2 * rand3();
    double brute = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < a.size(); ++i) {
      brute = std::min(brute, (a[i] + closest_on_segment(p, a[i], b[i]) * (b[i] - a[i]) - p).norm());
    }
    const SegmentSet::Hit hit = set.nearest(p);
    EXPECT_NEAR(hit.distance_m, brute, 1e-12);
    const Vector3d on = a[hit.segment] + hit.t * (b[hit.segment] - a[hit.segment]);
    EXPECT_NEAR((on - p).norm(), brute, 1e-12);
    int within = 0;
    set.visit_within(p, brute + 0.05, [&](const SegmentSet::Hit& h) {
      EXPECT_LE(h.distance_m, brute + 0.05);
      ++within;
    });
    int brute_within = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      brute_within += (a[i] + closest_on_segment(p, a[i], b[i]) * (b[i] - a[i]) - p).norm() <= brute + 0.05;
    }
    EXPECT_EQ(within, brute_within);
  }
  EXPECT_EQ(SegmentSet({}, {}).nearest(Vector3d::Zero()).segment, -1);
}

}  // namespace
}  // namespace pcisim::modeling
