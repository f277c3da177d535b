// The coronary tree skinned to an epicardium: here a 50 mm sphere (the phantom's heart) that the
// tests move rigidly or squeeze, so the expected positions are known exactly.
#include "physics/motion/vessel_skin.h"

#include <gtest/gtest.h>

#include <limits>

#include <Eigen/Geometry>
#include <cmath>
#include <map>

#include "anatomy/phantom/coronary_phantom.h"

namespace pcisim::physics {
namespace {

struct Surface {
  Eigen::Matrix3Xd points_m;
  std::vector<std::array<int, 3>> triangles;
};

// icosphere: subdivided icosahedron, outward counter-clockwise triangles
Surface sphere(double radius_m, int subdivisions) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f = g;
  }
  Surface s;
  s.points_m.resize(3, static_cast<int>(v.size()));
  for (int i = 0; i < static_cast<int>(v.size()); ++i) s.points_m.col(i) = radius_m * v[i];
  s.triangles = f;
  return s;
}

class VesselSkinTest : public ::testing::Test {
 protected:
  anatomy::VesselTree tree = anatomy::make_coronary_phantom({1});
  Surface heart = sphere(0.050, 4);
  VesselSkin skin{tree, heart.points_m, heart.triangles, VesselMotionParams{}};
};

TEST_F(VesselSkinTest, AtRestEveryPointStaysWhereItIs) {
  skin.update(heart.points_m);
  ASSERT_GT(skin.point_count(), 500);
  for (int i = 0; i < skin.point_count(); ++i)
    EXPECT_LT((skin.points_m()[i] - skin.rest_points_m()[i]).norm(), 1e-12) << i;
}

TEST_F(VesselSkinTest, CoronariesRideTheHeartAndTheAorticRootStays) {
  const auto offsets = skin.branch_offsets();
  const int aorta = tree.find("aorta"), lad = tree.find("LAD");
  // the LAD lies on the epicardium: fully attached
  for (int i = offsets[lad]; i < offsets[lad + 1]; ++i) EXPECT_EQ(skin.ride_weight(i), 1.0) << i;
  // the ascending aorta's far end is well off the heart
  EXPECT_EQ(skin.ride_weight(offsets[aorta + 1] - 1), 0.0);
}

TEST_F(VesselSkinTest, RigidHeartMotionCarriesAttachedPointsRigidly) {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.2, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(0.004, -0.002, 0.003);
  Eigen::Matrix3Xd moved = (r * heart.points_m).colwise() + t;
  skin.update(moved);
  int attached = 0;
  for (int i = 0; i < skin.point_count(); ++i) {
    if (skin.ride_weight(i) < 1.0) continue;
    ++attached;
    EXPECT_LT((skin.points_m()[i] - (r * skin.rest_points_m()[i] + t)).norm(), 1e-12) << i;
  }
  EXPECT_GT(attached, skin.point_count() / 2);
}

TEST_F(VesselSkinTest, SqueezedHeartKeepsTheTreeAtItsHeightAboveTheSurface) {
  // a 10 % radial squeeze (systole-like): a bound point keeps its height above the surface
  skin.update(0.9 * heart.points_m);
  const auto lad = tree.find("LAD");
  const auto offsets = skin.branch_offsets();
  for (int i = offsets[lad]; i < offsets[lad + 1]; ++i) {
    const double rest_height = skin.rest_points_m()[i].norm() - 0.050;
    const double height = skin.points_m()[i].norm() - 0.9 * 0.050;
    // the chordal triangles sit inside the sphere by up to R (1 - cos(edge/2R)) ~ 0.05 mm
    EXPECT_NEAR(height, rest_height, 1e-4) << i;
  }
}

TEST_F(VesselSkinTest, PointsInsideTheLumenMoveWithTheirVessel) {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.035, Eigen::Vector3d::UnitZ()).toRotationMatrix();  // 2 deg
  const Eigen::Vector3d t(0.003, 0.001, -0.002);
  skin.update(Eigen::Matrix3Xd((r * heart.points_m).colwise() + t));
  const auto& lad = tree.branches[tree.find("LAD")];
  for (size_t k = 10; k + 10 < lad.points.size(); k += 17) {
    // 1 mm off the axis, inside the lumen
    const Eigen::Vector3d axis = lad.points[k].position_m;
    const Eigen::Vector3d tangent = (lad.points[k + 1].position_m - lad.points[k - 1].position_m).normalized();
    const Eigen::Vector3d p = axis + 0.001 * tangent.unitOrthogonal();
    const Eigen::Vector3d exact = r * p + t;
    // the blend takes the centerline's motion; off the axis a rotation adds |w| x offset
    EXPECT_LT((skin.to_world(p) - exact).norm(), 1e-4) << k;
    EXPECT_LT((skin.to_rest(skin.to_world(p)) - p).norm(), 1e-6) << k;
    EXPECT_TRUE(skin.carries(p)) << k;
  }
  // inside the tree's grid but beyond every centerline's blend radius: nothing carries it
  const Eigen::Vector3d axis = lad.points[lad.points.size() / 2].position_m;
  const Eigen::Vector3d tangent =
      (lad.points[lad.points.size() / 2 + 1].position_m - lad.points[lad.points.size() / 2 - 1].position_m)
          .normalized();
  int beyond = 0;
  for (double off_m : {0.0045, 0.006, 0.008}) {
    const Eigen::Vector3d q = axis + off_m * tangent.unitOrthogonal();
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& c : skin.rest_points_m()) nearest = std::min(nearest, (c - q).norm());
    EXPECT_EQ(skin.carries(q), nearest < VesselMotionParams{}.blend_radius_m) << off_m << " m off, nearest " << nearest;
    if (!skin.carries(q)) {
      ++beyond;
      EXPECT_EQ(skin.displacement_m(q), Eigen::Vector3d::Zero()) << off_m;
    }
  }
  EXPECT_GT(beyond, 0) << "a probe beyond every blend radius";
  // far from every vessel nothing moves: nothing carries it
  EXPECT_EQ(skin.displacement_m(Eigen::Vector3d(0.3, 0.3, 0.3)), Eigen::Vector3d::Zero());
  EXPECT_FALSE(skin.carries(Eigen::Vector3d(0.3, 0.3, 0.3)));
  EXPECT_FALSE(skin.carries(Eigen::Vector3d(std::nan(""), 0, 0)));
  EXPECT_EQ(skin.displacement_m(Eigen::Vector3d(std::nan(""), 0, 0)), Eigen::Vector3d::Zero());
}

TEST_F(VesselSkinTest, BadTrianglesAreRefusedByName) {
  std::vector<std::array<int, 3>> bad = {{0, 1, 100000}};
  try {
    VesselSkin s(tree, heart.points_m, bad, VesselMotionParams{});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("vessel_motion"), std::string::npos) << e.what();
  }
}

TEST_F(VesselSkinTest, BadDistancesAreRefusedByName) {
  for (const char* field : {"attach_distance_m", "fade_distance_m", "blend_radius_m"}) {
    VesselMotionParams p;
    const std::string f = field;
    (f == "attach_distance_m" ? p.attach_distance_m
     : f == "fade_distance_m" ? p.fade_distance_m
                              : p.blend_radius_m) = std::nan("");
    try {
      VesselSkin s(tree, heart.points_m, heart.triangles, p);
      FAIL() << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("vessel_motion." + f, 0), 0u) << e.what();
    }
  }
}

// a force on a node in the lumen, carried to the world: the heart turned rigidly turns it with
// the heart (its length kept), whatever its direction: along the vessel or across it (the wall's
// push is across)
TEST_F(VesselSkinTest, AVectorInTheLumenTurnsWithTheHeart) {
  const double angle = 0.2;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(0.004, -0.002, 0.003);
  skin.update(Eigen::Matrix3Xd((r * heart.points_m).colwise() + t));
  const auto& lad = tree.branches[tree.find("LAD")];
  double worst_along = 0, worst_across = 0;
  for (size_t k = 10; k + 10 < lad.points.size(); k += 17) {
    const Eigen::Vector3d axis = lad.points[k].position_m;
    const Eigen::Vector3d tangent = (lad.points[k + 1].position_m - lad.points[k - 1].position_m).normalized();
    const Eigen::Vector3d across = tangent.unitOrthogonal(), across2 = tangent.cross(across);
    const Eigen::Vector3d p = axis + 0.0005 * across;
    for (const Eigen::Vector3d& v : {Eigen::Vector3d(0.3 * tangent), Eigen::Vector3d(-0.2 * across),
                                     Eigen::Vector3d(0.1 * across2), Eigen::Vector3d(0.2 * (across + tangent))}) {
      const Eigen::Vector3d turned = skin.turn_to_world(p, v);
      EXPECT_NEAR(turned.norm(), v.norm(), 1e-12) << "its length kept";
      const double off = std::acos(std::clamp(turned.normalized().dot((r * v).normalized()), -1.0, 1.0));
      (std::abs(v.normalized().dot(tangent)) > 0.99 ? worst_along : worst_across) =
          std::max(std::abs(v.normalized().dot(tangent)) > 0.99 ? worst_along : worst_across, off);
    }
  }
  std::printf("turned off the heart's turn (%.1f deg): along the vessel %.3f deg, across %.3f deg\n",
              angle * 180 / M_PI, worst_along * 180 / M_PI, worst_across * 180 / M_PI);
  EXPECT_LT(worst_along, 0.02 * angle);
  EXPECT_LT(worst_across, 0.02 * angle);
  // a zero or non-finite vector comes back as it is
  EXPECT_EQ(skin.turn_to_world(lad.points[20].position_m, Eigen::Vector3d::Zero()), Eigen::Vector3d::Zero());
  EXPECT_TRUE(std::isnan(skin.turn_to_world(lad.points[20].position_m, Eigen::Vector3d(NAN, 0, 0)).x()));
}

}  // namespace
}  // namespace pcisim::physics
