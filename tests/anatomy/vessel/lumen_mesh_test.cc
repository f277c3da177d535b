#include "anatomy/vessel/lumen_mesh.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <map>
#include <numbers>
#include <utility>

#include "anatomy/phantom/coronary_phantom.h"

namespace pcisim::anatomy {
namespace {

// closed and consistently oriented: every directed edge appears once and its reverse once
void expect_closed_and_consistent(const TriangleMesh& m, const std::string& what) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : m.triangles) {
    for (int e = 0; e < 3; ++e) ++directed[{t[e], t[(e + 1) % 3]}];
  }
  int bad = 0;
  for (const auto& [edge, count] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    if (count != 1 || reverse == directed.end() || reverse->second != 1) ++bad;
  }
  EXPECT_EQ(bad, 0) << what << ": edges not shared by exactly two opposite triangles";
}

double signed_volume_m3(const TriangleMesh& m) {
  double v = 0.0;
  for (const auto& t : m.triangles) {
    v += m.vertices_m[t[0]].dot(m.vertices_m[t[1]].cross(m.vertices_m[t[2]])) / 6.0;
  }
  return v;
}

VesselTree straight_tube(double radius_m, double length_m) {
  VesselTree tree;
  VesselBranch b;
  b.name = "tube";
  const int n = static_cast<int>(length_m / 0.5e-3);
  for (int i = 0; i <= n; ++i) b.points.push_back({Eigen::Vector3d(length_m * i / n, 0.001, -0.002), radius_m});
  tree.branches.push_back(b);
  return tree;
}

TEST(LumenMeshTest, StraightTubeIsAClosedCapsuleOfTheRightVolume) {
  const double r = 1.5e-3, len = 10e-3;
  LumenMeshSpec spec;
  spec.segments = 48;
  spec.cap_rings = 12;
  const auto tubes = loft_branch_tubes(straight_tube(r, len), spec);
  ASSERT_EQ(tubes.size(), 1u);
  expect_closed_and_consistent(tubes[0], "straight tube");
  const double capsule = std::numbers::pi * r * r * len + 4.0 / 3.0 * std::numbers::pi * r * r * r;
  // polygon sag: 48 segments and 12 cap rings lose well under 2 %
  EXPECT_NEAR(signed_volume_m3(tubes[0]), capsule, 0.02 * capsule);
  EXPECT_GT(signed_volume_m3(tubes[0]), 0.0) << "faces must wind outward";
  // every vertex lies on the capsule surface
  for (const auto& v : tubes[0].vertices_m) {
    const double x = std::clamp(v.x(), 0.0, len);
    EXPECT_NEAR((v - Eigen::Vector3d(x, 0.001, -0.002)).norm(), r, 1e-12);
  }
}

TEST(LumenMeshTest, EveryPhantomTubeIsClosedAndOutward) {
  const VesselTree tree = make_coronary_phantom({});
  const auto tubes = loft_branch_tubes(tree, {});
  ASSERT_EQ(tubes.size(), tree.branches.size());
  for (size_t i = 0; i < tubes.size(); ++i) {
    const auto& b = tree.branches[i];
    ASSERT_FALSE(tubes[i].triangles.empty()) << b.name;
    expect_closed_and_consistent(tubes[i], b.name);
    // ~ the swept volume, sum of pi r^2 ds
    double swept = 0.0;
    for (size_t k = 1; k < b.points.size(); ++k) {
      const double rr = 0.5 * (b.points[k].radius_m + b.points[k - 1].radius_m);
      swept += std::numbers::pi * rr * rr * (b.points[k].position_m - b.points[k - 1].position_m).norm();
    }
    // plus the two hemispherical caps
    const double r0 = b.points.front().radius_m, r1 = b.points.back().radius_m;
    swept += 2.0 / 3.0 * std::numbers::pi * (r0 * r0 * r0 + r1 * r1 * r1);
    EXPECT_GT(signed_volume_m3(tubes[i]), 0.95 * swept) << b.name;
    EXPECT_LT(signed_volume_m3(tubes[i]), 1.05 * swept) << b.name;
  }
  // the union mesh keeps each tube's triangles and re-indexes them
  const TriangleMesh lumen = loft_lumen(tree, {});
  size_t tris = 0;
  for (const auto& t : tubes) tris += t.triangles.size();
  EXPECT_EQ(lumen.triangles.size(), tris);
  expect_closed_and_consistent(lumen, "union");
}

TEST(LumenMeshTest, ChordErrorBoundAddsSegmentsToWideTubes) {
  const VesselTree tree = make_coronary_phantom({});
  LumenMeshSpec spec;  // 16 segments, 0.05 mm sag
  const auto tubes = loft_branch_tubes(tree, spec);
  const double r = tree.branches[tree.find("aorta")].points[0].radius_m;
  const auto& aorta = tubes[tree.find("aorta")];
  const auto& ring0_a = aorta.vertices_m[0];
  const auto& ring0_b = aorta.vertices_m[1];
  // neighbouring ring vertices are close enough that the chord sags < 0.05 mm
  const double chord = (ring0_a - ring0_b).norm();
  EXPECT_LT(r - std::sqrt(r * r - chord * chord / 4), 0.05e-3 + 1e-9);
}

TEST(LumenMeshTest, ExcludedBranchesAreLeftOut) {
  const VesselTree tree = make_coronary_phantom({});
  LumenMeshSpec spec;
  spec.exclude = {"aorta"};
  const auto tubes = loft_branch_tubes(tree, spec);
  EXPECT_TRUE(tubes[tree.find("aorta")].triangles.empty());
  EXPECT_FALSE(tubes[tree.find("LM")].triangles.empty());
}

TEST(LumenMeshTest, ChildOffTheParentCenterlineStartsInsideTheParent) {
  // a side branch whose first point sits on the parent's wall is extended back into the parent
  VesselTree tree = straight_tube(2e-3, 10e-3);
  VesselBranch side;
  side.name = "side";
  side.parent = 0;
  side.parent_point = 10;
  const Eigen::Vector3d on_wall = tree.branches[0].points[10].position_m + Eigen::Vector3d(0, 2e-3, 0);
  for (int i = 0; i <= 10; ++i) side.points.push_back({on_wall + Eigen::Vector3d(0, 0.5e-3 * i, 0), 0.8e-3});
  tree.branches.push_back(side);
  const auto tubes = loft_branch_tubes(tree, {});
  expect_closed_and_consistent(tubes[1], "side");
  double min_y = 1.0;
  for (const auto& v : tubes[1].vertices_m) min_y = std::min(min_y, v.y() - 0.001);
  EXPECT_LT(min_y, 0.5e-3) << "the side tube should reach well inside the parent's 2 mm lumen";
}

}  // namespace
}  // namespace pcisim::anatomy
