// Surface distance and Dice on shapes with exact answers: concentric spheres and closed
// cylinders (meshes made here), coaxial rounded cylinders as vessel trees.
#include "modeling/evaluation/lumen_scores.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <unordered_map>
#include <utility>

namespace pcisim::modeling {
namespace {

using anatomy::TriangleMesh;
using anatomy::VesselTree;
using Eigen::Vector3d;

constexpr double kMm = 1e-3;
constexpr double kPi = std::numbers::pi;

// an icosahedron split `levels` times, its vertices on the sphere of radius r_mm about c_mm
TriangleMesh icosphere(double r_mm, int levels, const Vector3d& c_mm = Vector3d::Zero()) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vector3d> v = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                             {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::unordered_map<int64_t, int> mid;
    auto midpoint = [&](int a, int b) {
      const int64_t key = int64_t{std::min(a, b)} << 32 | std::max(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& [a, b, c] : f) {
      const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      next.insert(next.end(), {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}});
    }
    f = std::move(next);
  }
  TriangleMesh m;
  for (const auto& p : v) m.vertices_m.push_back((c_mm + r_mm * p) * kMm);
  m.triangles = f;
  return m;
}

// a closed cylinder about the z axis: `sides` flat faces (vertices on radius r_mm), z in
// [-length/2, length/2], caps fanned from their centres
TriangleMesh cylinder(double r_mm, double length_mm, int sides, int rings) {
  TriangleMesh m;
  for (int k = 0; k <= rings; ++k) {
    const double z = length_mm * (double(k) / rings - 0.5);
    for (int i = 0; i < sides; ++i) {
      const double a = 2 * kPi * i / sides;
      m.vertices_m.push_back(Vector3d(r_mm * std::cos(a), r_mm * std::sin(a), z) * kMm);
    }
  }
  auto at = [&](int k, int i) { return k * sides + (i % sides); };
  for (int k = 0; k < rings; ++k) {
    for (int i = 0; i < sides; ++i) {
      m.triangles.push_back({at(k, i), at(k, i + 1), at(k + 1, i + 1)});
      m.triangles.push_back({at(k, i), at(k + 1, i + 1), at(k + 1, i)});
    }
  }
  const int bottom = static_cast<int>(m.vertices_m.size()), top = bottom + 1;
  m.vertices_m.push_back(Vector3d(0, 0, -length_mm / 2) * kMm);
  m.vertices_m.push_back(Vector3d(0, 0, length_mm / 2) * kMm);
  for (int i = 0; i < sides; ++i) {
    m.triangles.push_back({bottom, at(0, i + 1), at(0, i)});
    m.triangles.push_back({top, at(rings, i), at(rings, i + 1)});
  }
  return m;
}

TEST(LumenScores, IdenticalMeshesAreZeroApart) {
  const TriangleMesh s = icosphere(2.0, 3);
  const LumenScores l = score_lumen(s, s, 0.1 * kMm);
  EXPECT_NEAR(l.mean_mm, 0, 1e-12);
  EXPECT_NEAR(l.hausdorff95_mm, 0, 1e-12);
  EXPECT_NEAR(l.max_mm, 0, 1e-12);
}

TEST(LumenScores, ConcentricSpheresAreTheRadiusDifferenceApart) {
  // scaled copies of one icosphere: flat faces lie parallel, 0.5 mm times the cosine of a face's
  // angular size (~2 degrees at 4 levels) apart
  const LumenScores l = score_lumen(icosphere(2.0, 4), icosphere(2.5, 4), 0.1 * kMm);
  EXPECT_NEAR(l.mean_mm, 0.5, 1e-3);
  EXPECT_NEAR(l.hausdorff95_mm, 0.5, 1e-3);
  EXPECT_NEAR(l.reference_to_extracted_mean_mm, 0.5, 1e-3);
  EXPECT_NEAR(l.extracted_to_reference_mean_mm, 0.5, 1e-3);
  EXPECT_LE(l.max_mm, 0.5 + 1e-9);
  EXPECT_GT(l.samples, 2 * 5120);  // about one point per 0.01 mm^2 of 50 + 79 mm^2
}

TEST(LumenScores, ConcentricClosedCylinders) {
  // outer: radius and half-length 0.5 mm more. From inside, the outer surface is 0.5 mm away
  // everywhere (to within the facets' cos(pi/sides)); from outside, farther past the inner rims:
  // sqrt(0.5^2 + s^2) at s past a rim, integrated over the outer surface here
  const double r1 = 1.0, r2 = 1.5, l1 = 8.0, l2 = 9.0, d = 0.5;
  const int sides = 128;
  const LumenScores l = score_lumen(cylinder(r1, l1, sides, 16), cylinder(r2, l2, sides, 18), 0.1 * kMm);
  EXPECT_NEAR(l.reference_to_extracted_mean_mm, d, 1e-3);
  double sum = 0, area = 0;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const double s = d * (i + 0.5) / n, ds = d / n;
    const double far = std::hypot(d, s);
    sum += 2 * 2 * kPi * r2 * far * ds;        // the side beyond either inner cap
    sum += 2 * 2 * kPi * (r1 + s) * far * ds;  // the cap annuli beyond the inner rim
    area += 2 * 2 * kPi * r2 * ds + 2 * 2 * kPi * (r1 + s) * ds;
  }
  sum += (2 * kPi * r2 * l1 + 2 * kPi * r1 * r1) * d;  // facing the inner side and caps
  area += 2 * kPi * r2 * l1 + 2 * kPi * r1 * r1;
  EXPECT_NEAR(area, 2 * kPi * r2 * l2 + 2 * kPi * r2 * r2, 1e-9);
  EXPECT_NEAR(l.extracted_to_reference_mean_mm, sum / area, 2e-3);
  EXPECT_GT(l.max_mm, d * std::sqrt(2.0) - 0.1);  // the outer rim to the inner rim, within a spacing
  EXPECT_LE(l.max_mm, d * std::sqrt(2.0) + 1e-9);
}

TEST(LumenScores, OffsetSpheresOfAHundredThousandTriangles) {
  // radii 3 and 3.2 mm, centres 0.05 mm apart: to first order a point facing direction n is
  // 0.2 + 0.05 n_x mm from the other sphere, and n_x is uniform on [-1, 1] over a sphere's area
  // (Archimedes), so the mean is 0.2 mm and the 95th percentile 0.2 + 0.05 * 0.9 mm; the second
  // order adds at most 0.05^2 / (2 * 3) mm
  const TriangleMesh a = icosphere(3.0, 6), b = icosphere(3.2, 5, {0.05, 0, 0});  // 81920 + 20480
  const LumenScores l = score_lumen(a, b, 0.1 * kMm);
  EXPECT_NEAR(l.mean_mm, 0.2, 1e-3);
  EXPECT_NEAR(l.hausdorff95_mm, 0.245, 1e-3);
  EXPECT_NEAR(l.max_mm, 0.25, 1e-3);
  // one point per triangle at least (the finer's edges are ~0.05 mm); brute force would test
  // 10^10 point-triangle pairs (no time is asserted here: speed belongs in benchmarks)
  EXPECT_GE(l.samples, 81920 + 20480);
}

TEST(LumenScores, RefusesBadInput) {
  const TriangleMesh s = icosphere(1.0, 1);
  EXPECT_THROW(score_lumen(s, s, 0), std::invalid_argument);
  TriangleMesh bad = s;
  bad.triangles.push_back({0, 1, 9999});
  EXPECT_THROW(score_lumen(s, bad, 0.1 * kMm), std::invalid_argument);
  EXPECT_TRUE(std::isnan(score_lumen(s, TriangleMesh{}, 0.1 * kMm).mean_mm));
}

// a straight vessel from a_mm to b_mm of radius r_mm, a point every mm
VesselTree rod(const Vector3d& a_mm, const Vector3d& b_mm, double r_mm) {
  VesselTree t;
  t.branches.push_back({"LAD", -1, -1, {}});
  const int n = static_cast<int>(std::lround((b_mm - a_mm).norm()));
  for (int i = 0; i <= n; ++i) t.branches[0].points.push_back({(a_mm + (b_mm - a_mm) * i / n) * kMm, r_mm * kMm});
  return t;
}

TEST(LumenScores, DiceOfCoaxialCylinders) {
  // 10 mm long rods with ball ends, radii 1 and 1.5 mm, along an oblique axis: Dice
  // 2 V1 / (V1 + V2) with V = pi r^2 L + 4/3 pi r^3 (2 r1^2 / (r1^2 + r2^2) without the ends)
  const Vector3d a(0.3, -0.2, 0.1), b = a + 10 * Vector3d(1, 2, 2).normalized();
  const double r1 = 1.0, r2 = 1.5, len = 10;
  auto volume = [&](double r) { return kPi * r * r * len + 4.0 / 3 * kPi * r * r * r; };
  const double expected = 2 * volume(r1) / (volume(r1) + volume(r2));
  EXPECT_NEAR(dice_of_trees(rod(a, b, r1), rod(a, b, r2), 0.05 * kMm), expected, 2e-3);
  EXPECT_DOUBLE_EQ(dice_of_trees(rod(a, b, r1), rod(a, b, r1), 0.05 * kMm), 1.0);
}

TEST(LumenScores, DiceVisitsOnlyVoxelsNearTheTrees) {
  // half a metre apart at 0.05 mm voxels: a dense grid would hold 10^13 voxels (and never end)
  const double dice = dice_of_trees(rod({0, 0, 0}, {10, 0, 0}, 1), rod({0, 500, 0}, {10, 500, 0}, 1), 0.05 * kMm);
  EXPECT_EQ(dice, 0.0);
  // the aorta is left out by name
  VesselTree with_aorta = rod({0, 0, 0}, {10, 0, 0}, 1);
  with_aorta.branches.insert(with_aorta.branches.begin(), rod({0, 0, -40}, {0, 0, 40}, 12).branches[0]);
  with_aorta.branches[0].name = "aorta";
  with_aorta.branches[1].parent = 0;
  with_aorta.branches[1].parent_point = 40;
  EXPECT_DOUBLE_EQ(dice_of_trees(with_aorta, rod({0, 0, 0}, {10, 0, 0}, 1), 0.1 * kMm), 1.0);
  EXPECT_TRUE(std::isnan(dice_of_trees(VesselTree{}, VesselTree{}, 0.1 * kMm)));
}

}  // namespace
}  // namespace pcisim::modeling
