#include "physics/sdf/signed_distance_field.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "physics/sdf/lumen_sdf.h"
#include "anatomy/phantom/coronary_phantom.h"
#include "anatomy/vessel/lumen_mesh.h"

namespace pcisim::physics {
namespace {

constexpr double kR = 1.5e-3, kLen = 10e-3, kH = 0.2e-3;
const Eigen::Vector3d kAxis0(0.0, 1e-3, -2e-3);

// a straight 1.5 mm tube along x with hemispherical ends: the capsule has a closed-form distance
anatomy::TriangleMesh capsule_mesh() {
  anatomy::VesselTree tree;
  anatomy::VesselBranch b;
  b.name = "tube";
  for (int i = 0; i <= 20; ++i) b.points.push_back({kAxis0 + Eigen::Vector3d(kLen * i / 20, 0, 0), kR});
  tree.branches.push_back(b);
  anatomy::LumenMeshSpec spec;
  spec.segments = 64;  // sag 1.5 mm * (1 - cos(pi/64)) < 2 um
  spec.cap_rings = 12;
  return anatomy::loft_lumen(tree, spec);
}

double capsule_distance(const Eigen::Vector3d& p) {
  const double x = std::clamp(p.x() - kAxis0.x(), 0.0, kLen);
  return (p - kAxis0 - Eigen::Vector3d(x, 0, 0)).norm() - kR;
}

const SignedDistanceField& capsule_sdf() {
  static const SignedDistanceField sdf = [] {
    SdfBuildSpec spec;
    spec.spacing_m = kH;
    spec.padding_m = 1e-3;
    spec.band_m = 1.6e-3;  // wider than the radius, so the axis holds true distances
    return SignedDistanceField::build(capsule_mesh(), spec);
  }();
  return sdf;
}

TEST(SdfTest, NegativeAboutMinusRadiusOnTheCenterline) {
  const auto& sdf = capsule_sdf();
  for (int i = 0; i <= 40; ++i) {
    const Eigen::Vector3d p = kAxis0 + Eigen::Vector3d(kLen * i / 40, 0, 0);
    const SdfSample s = sdf.sample(p);
    EXPECT_TRUE(s.inside_grid);
    // the distance has a ridge on the axis that trilinear interpolation rounds off by < 1 cell
    EXPECT_NEAR(s.distance_m, -kR, kH) << "x = " << p.x();
    EXPECT_LT(s.distance_m, -kR + kH);
  }
}

TEST(SdfTest, TrilinearValueWithinHalfACellOfTheAnalyticDistance) {
  const auto& sdf = capsule_sdf();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  for (int n = 0; n < 20000; ++n) {
    const Eigen::Vector3d p = kAxis0 + Eigen::Vector3d(kLen * (0.5 + 0.7 * u(rng)), 3.2e-3 * u(rng), 3.2e-3 * u(rng));
    const double exact = capsule_distance(p);
    if (std::abs(exact) > sdf.band_m() - kH) continue;  // the clamped band edge
    if (exact < -kR + kH) continue;                     // the axis ridge: previous test
    const SdfSample s = sdf.sample(p);
    ASSERT_NEAR(s.distance_m, exact, 0.5 * kH) << p.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 5000);
}

TEST(SdfTest, PositiveOutsideTheWall) {
  const auto& sdf = capsule_sdf();
  for (int a = 0; a < 12; ++a) {
    const double phi = a * 2 * M_PI / 12;
    const Eigen::Vector3d radial(0, std::cos(phi), std::sin(phi));
    const Eigen::Vector3d p = kAxis0 + Eigen::Vector3d(5e-3, 0, 0) + (kR + 0.3e-3) * radial;
    const SdfSample s = sdf.sample(p);
    EXPECT_GT(s.distance_m, 0.0);
    EXPECT_NEAR(s.distance_m, 0.3e-3, 0.5 * kH);
  }
  // beyond the band (in a corner of the grid box): clamped to +band
  const SdfSample far = sdf.sample(kAxis0 + Eigen::Vector3d(5e-3, 2.4e-3, 2.4e-3));
  EXPECT_TRUE(far.inside_grid);
  EXPECT_NEAR(far.distance_m, sdf.band_m(), 1e-7);
}

TEST(SdfTest, GradientIsUnitAndRadial) {
  const auto& sdf = capsule_sdf();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int n = 0; n < 2000; ++n) {
    // 1.0 .. 2.2 mm from the axis (nearer the axis the grid is coarse against the curvature)
    const double rho = 1.0e-3 + 1.2e-3 * u(rng);
    const double phi = 2 * M_PI * u(rng);
    const Eigen::Vector3d radial(0, std::cos(phi), std::sin(phi));
    const Eigen::Vector3d p = kAxis0 + Eigen::Vector3d(2e-3 + 6e-3 * u(rng), 0, 0) + rho * radial;
    const SdfSample s = sdf.sample(p);
    EXPECT_NEAR(s.gradient.norm(), 1.0, 1e-12);
    // the interpolant bends the normal by about half a cell over the radius of curvature
    const double allowed_rad = 0.6 * kH / rho + 0.01;
    EXPECT_GT(s.gradient.dot(radial), std::cos(allowed_rad)) << "rho " << rho << " at " << p.transpose();
  }
}

TEST(SdfTest, OutsideTheGridIsFiniteAndPointsBackOut) {
  const auto& sdf = capsule_sdf();
  const Eigen::Vector3d box_lo = sdf.origin_m();
  const Eigen::Vector3d box_hi = box_lo + sdf.spacing_m() * (sdf.dims() - Eigen::Vector3i::Ones()).cast<double>();
  const Eigen::Vector3d probes[] = {box_hi + Eigen::Vector3d(0.01, 0, 0), box_lo - Eigen::Vector3d(0, 0.5, 0),
                                    Eigen::Vector3d(1e6, -1e6, 3e5), box_hi + Eigen::Vector3d(1e-3, 2e-3, 3e-3)};
  for (const Eigen::Vector3d& p : probes) {
    const SdfSample s = sdf.sample(p);
    EXPECT_FALSE(s.inside_grid);
    ASSERT_TRUE(std::isfinite(s.distance_m));
    EXPECT_TRUE(s.gradient.allFinite());
    EXPECT_NEAR(s.gradient.norm(), 1.0, 1e-12);
    // at least the distance from the box; the gradient leads from the box toward the point
    const Eigen::Vector3d on_box = p.cwiseMax(box_lo).cwiseMin(box_hi);
    EXPECT_GE(s.distance_m, (p - on_box).norm());
    EXPECT_GT(s.gradient.dot((p - on_box).normalized()), 0.999);
  }
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(nan, 0, 0), Eigen::Vector3d(0, inf, 0), Eigen::Vector3d(0, 0, -inf)}) {
    const SdfSample s = sdf.sample(p);
    EXPECT_FALSE(s.inside_grid);
    EXPECT_EQ(s.distance_m, 1.0) << "non-finite points are reported 1 m outside";
    EXPECT_EQ(s.gradient, Eigen::Vector3d::UnitX());
  }
  // a default field has no grid: every point is far outside
  const SdfSample none = SignedDistanceField().sample(Eigen::Vector3d::Zero());
  EXPECT_FALSE(none.inside_grid);
  EXPECT_GT(none.distance_m, 0.0);
}

// rows of the grid running exactly through ring vertices, along mesh edges (tangent to the tube)
// and through both cap poles: the parity rule must still count crossings right everywhere
TEST(SdfTest, GridAlignedTubeHasNoSignErrors) {
  const double r = 1.6e-3, h = 0.2e-3, len = 4e-3;
  anatomy::VesselTree tree;
  anatomy::VesselBranch b;
  b.name = "aligned";
  for (int i = 0; i <= 8; ++i) b.points.push_back({Eigen::Vector3d(len * i / 8, 0, 0), r});
  tree.branches.push_back(b);
  anatomy::LumenMeshSpec mesh_spec;
  mesh_spec.segments = 16;
  mesh_spec.cap_rings = 4;
  mesh_spec.max_chord_error_m = 0.0;  // exactly 16 segments: vertices at 0, 22.5, 45, 90 deg
  SdfBuildSpec spec;
  spec.spacing_m = h;
  spec.padding_m = 0.4e-3;  // origin at -(r + padding) = -10 cells: rows through y = 0, z = 0, z = r
  spec.band_m = 0.4e-3;     // thinner than the radius: the middle relies on parity alone
  const SignedDistanceField sdf = SignedDistanceField::build(anatomy::loft_lumen(tree, mesh_spec), spec);
  ASSERT_NEAR(sdf.origin_m().y(), -2.0e-3, 1e-12);
  const double sag = r * (1 - std::cos(M_PI / 16)) + 1e-6;
  int checked = 0;
  for (int k = 0; k < sdf.dims().z(); ++k)
    for (int j = 0; j < sdf.dims().y(); ++j)
      for (int i = 0; i < sdf.dims().x(); ++i) {
        const Eigen::Vector3d p = sdf.origin_m() + h * Eigen::Vector3d(i, j, k);
        const double x = std::clamp(p.x(), 0.0, len);
        const double exact = (p - Eigen::Vector3d(x, 0, 0)).norm() - r;
        if (std::abs(exact) < 2 * sag) continue;  // the polygon and the capsule differ here
        const float v = sdf.value_at(i, j, k);
        ASSERT_EQ(v < 0, exact < 0) << "grid point " << i << " " << j << " " << k << " value " << v << " exact "
                                    << exact;
        ++checked;
      }
  EXPECT_GT(checked, 10000);
}

TEST(SdfTest, BadInputsThrow) {
  EXPECT_THROW(SignedDistanceField::build(anatomy::TriangleMesh{}, 0.2e-3, 1e-3), std::invalid_argument);
  EXPECT_THROW(SignedDistanceField::build(capsule_mesh(), 0.0, 1e-3), std::invalid_argument);
  EXPECT_THROW(SignedDistanceField::build(capsule_mesh(), NAN, 1e-3), std::invalid_argument);
  EXPECT_THROW(SignedDistanceField::build(capsule_mesh(), 1e-9, 1e-3), std::invalid_argument) << "grid too large";
}

// the phantom's lumen is a union of overlapping tubes: no wall of one tube may show inside another
class SdfPhantomTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tree_ = new anatomy::VesselTree(anatomy::make_coronary_phantom({}));
    sdf_ = new SignedDistanceField(build_lumen_sdf(*tree_, 0.2e-3));
  }
  static void TearDownTestSuite() {
    delete sdf_;
    delete tree_;
  }
  static const anatomy::VesselBranch& branch(const char* name) { return tree_->branches.at(tree_->find(name)); }
  static anatomy::VesselTree* tree_;
  static SignedDistanceField* sdf_;
};
anatomy::VesselTree* SdfPhantomTest::tree_ = nullptr;
SignedDistanceField* SdfPhantomTest::sdf_ = nullptr;

TEST_F(SdfPhantomTest, EveryCenterlinePointIsInside) {
  for (const auto& b : tree_->branches) {
    for (size_t k = 0; k < b.points.size(); ++k) {
      const SdfSample s = sdf_->sample(b.points[k].position_m);
      EXPECT_LT(s.distance_m, 0.0) << b.name << "[" << k << "]";
      EXPECT_TRUE(s.inside_grid);
    }
  }
}

TEST_F(SdfPhantomTest, NoFalseWallThroughTheForkOrTheOstium) {
  // dense samples along LM then LAD (and LM then LCx), through the fork
  for (const char* daughter : {"LAD", "LCx"}) {
    std::vector<Eigen::Vector3d> path;
    for (const auto& p : branch("LM").points) path.push_back(p.position_m);
    const auto& d = branch(daughter).points;
    for (size_t k = 0; k < 40; ++k) path.push_back(d[k].position_m);
    for (size_t k = 1; k < path.size(); ++k) {
      for (int s = 0; s < 5; ++s) {
        const Eigen::Vector3d p = path[k - 1] + (path[k] - path[k - 1]) * (s / 5.0);
        EXPECT_LT(sdf_->sample(p).distance_m, -0.3e-3) << daughter << " path point " << k << "." << s;
      }
    }
  }
  // the guide catheter's path lies in the aorta and ends in the LM: inside all the way
  for (const Eigen::Vector3d& p : anatomy::guide_catheter_path(*tree_)) EXPECT_LT(sdf_->sample(p).distance_m, 0.0);
}

TEST_F(SdfPhantomTest, TubeWallInsideTheAortaIsNotAWall) {
  // just outside the LM's own tube, where the LM still runs inside the aortic root
  const auto& aorta = branch("aorta");
  const auto& lm = branch("LM");
  const double aorta_r = aorta.points[0].radius_m;
  int checked = 0;
  for (size_t k = 2; k < lm.points.size(); ++k) {
    const Eigen::Vector3d c = lm.points[k].position_m;
    const Eigen::Vector3d t = (lm.points[k].position_m - lm.points[k - 1].position_m).normalized();
    const Eigen::Vector3d u = t.unitOrthogonal(), v = t.cross(u);
    for (int a = 0; a < 8; ++a) {
      const Eigen::Vector3d p =
          c + (lm.points[k].radius_m + 0.3e-3) * (std::cos(a * M_PI / 4) * u + std::sin(a * M_PI / 4) * v);
      double to_aorta_axis = 0;
      anatomy::nearest_branch(anatomy::VesselTree{{aorta}}, p, &to_aorta_axis);
      if (to_aorta_axis > aorta_r - 1.5e-3) continue;  // near or beyond the aortic wall
      EXPECT_LT(sdf_->sample(p).distance_m, 0.0) << "LM[" << k << "] angle " << a;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
  // the middle of the aortic root is deep inside: the clamped band, with a safe gradient
  const SdfSample deep = sdf_->sample(aorta.points[40].position_m);
  EXPECT_NEAR(deep.distance_m, -sdf_->band_m(), 1e-7);
  EXPECT_NEAR(deep.gradient.norm(), 1.0, 1e-12);
}

TEST_F(SdfPhantomTest, OutsideTheWallNextToEveryBranchIsPositive) {
  int checked = 0;
  for (const auto& b : tree_->branches) {
    if (b.name == "aorta" || b.name == "LM" || b.name == "RCA") continue;  // these start inside the aorta
    for (size_t k = b.points.size() / 3; k + 1 < b.points.size(); k += 20) {
      const Eigen::Vector3d c = b.points[k].position_m;
      const Eigen::Vector3d t = (b.points[k + 1].position_m - c).normalized();
      const Eigen::Vector3d u = t.unitOrthogonal(), v = t.cross(u);
      for (int a = 0; a < 6; ++a) {
        const Eigen::Vector3d radial = std::cos(a * M_PI / 3) * u + std::sin(a * M_PI / 3) * v;
        const Eigen::Vector3d p = c + (b.points[k].radius_m + 0.4e-3) * radial;
        double dc = 0;
        // skip spots where another branch passes close by
        if (anatomy::nearest_branch(*tree_, p, &dc) != tree_->find(b.name)) continue;
        const SdfSample s = sdf_->sample(p);
        EXPECT_GT(s.distance_m, 0.2e-3) << b.name << "[" << k << "]";
        EXPECT_GT(s.gradient.dot(radial), 0.9) << b.name << "[" << k << "]";
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100);
}

// independent check of every step (prisms, sign, union, parity): stored grid values against the
// analytic distance to the union of the centerline capsules (min over segments of distance minus
// the interpolated radius), clamped to the band. The mesh differs from the capsules by the ring
// polygon's sag (<= 0.05 mm; <= ~0.075 mm on the caps' facets, which sag both ways) and the
// rings' straight sides (~0.003 mm); grid values carry no interpolation error: 0.08 mm.
TEST_F(SdfPhantomTest, StoredValuesMatchTheAnalyticUnionOfCapsules) {
  const auto& table = sdf_->brick_table();
  std::vector<Eigen::Vector3i> stored;
  const Eigen::Vector3i bd = sdf_->brick_dims();
  for (int bz = 0; bz < bd.z(); ++bz)
    for (int by = 0; by < bd.y(); ++by)
      for (int bx = 0; bx < bd.x(); ++bx)
        if (table[bx + bd.x() * (by + bd.y() * bz)] >= 0) stored.push_back({bx, by, bz});
  ASSERT_FALSE(stored.empty());
  std::mt19937 rng(5);
  const double band = sdf_->band_m();
  int inside = 0, outside = 0;
  for (int n = 0; n < 4000; ++n) {
    const Eigen::Vector3i b = stored[rng() % stored.size()];
    const Eigen::Vector3i ijk = b * 8 + Eigen::Vector3i(rng() % 8, rng() % 8, rng() % 8);
    const Eigen::Vector3d p = sdf_->origin_m() + sdf_->spacing_m() * ijk.cast<double>();
    double exact = 1.0;
    for (const auto& br : tree_->branches) {
      for (size_t k = 1; k < br.points.size(); ++k) {
        const Eigen::Vector3d a = br.points[k - 1].position_m, ab = br.points[k].position_m - a;
        const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
        const double r = br.points[k - 1].radius_m + t * (br.points[k].radius_m - br.points[k - 1].radius_m);
        exact = std::min(exact, (a + t * ab - p).norm() - r);
      }
    }
    exact = std::clamp(exact, -band, band);
    const double stored_value = sdf_->value_at(ijk.x(), ijk.y(), ijk.z());
    ASSERT_NEAR(stored_value, exact, 0.08e-3) << "grid point " << ijk.transpose() << " at " << p.transpose();
    (exact < 0 ? inside : outside)++;
  }
  EXPECT_GT(inside, 500);
  EXPECT_GT(outside, 500);
}

}  // namespace
}  // namespace pcisim::physics
