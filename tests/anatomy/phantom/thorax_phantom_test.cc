#include "anatomy/phantom/thorax_phantom.h"

#include <gtest/gtest.h>

#include <cmath>

#include "anatomy/phantom/coronary_phantom.h"

namespace pcisim::anatomy {
namespace {

// HU of the voxel nearest to p_mm
double hu_at(const Volume& v, const Eigen::Vector3d& p_mm) {
  const Eigen::Vector3d ijk = v.physical_to_index(p_mm);
  const int64_t i = std::lround(ijk.x()), j = std::lround(ijk.y()), k = std::lround(ijk.z());
  EXPECT_TRUE(i >= 0 && j >= 0 && k >= 0 && i < v.dims[0] && j < v.dims[1] && k < v.dims[2]) << p_mm.transpose();
  return v.hu(i, j, k);
}

ThoraxPhantomSpec coarse() {
  ThoraxPhantomSpec s;
  s.dims = {112, 96, 64};
  s.spacing_mm = 3.0;
  return s;
}

TEST(ThoraxPhantom, TissuesWhereTheAnatomySaysSo) {
  const ThoraxPhantomSpec s = coarse();
  const Volume v = make_thorax_phantom(s);
  EXPECT_EQ(validate(v), "");
  EXPECT_EQ(v.type, VoxelType::kInt16);
  // heart centre: blood in a chamber or myocardium
  EXPECT_NEAR(hu_at(v, {0, 0, 0}), 42.5, 2.6);
  // lungs either side of the mediastinum
  EXPECT_EQ(hu_at(v, {-95, 40, 15}), s.hu.lung);
  EXPECT_EQ(hu_at(v, {85, 45, 20}), s.hu.lung);
  // outside the body: air
  EXPECT_EQ(hu_at(v, v.index_to_physical_mm({0, 0, 0})), s.hu.air);
  // subcutaneous fat at the lateral body wall (outline ~160 mm from the thorax centre)
  {
    const Eigen::Vector3d row = v.physical_to_index({0, 32, 0});
    int64_t i = 0;
    while (i < v.dims[0] && v.hu(i, std::lround(row.y()), std::lround(row.z())) == s.hu.air) ++i;
    ASSERT_LT(i, v.dims[0] / 2);
    EXPECT_EQ(v.hu(i, std::lround(row.y()), std::lround(row.z())), s.hu.fat);
  }
  // a vertebral body's cancellous core and the spinal canal behind it
  EXPECT_EQ(hu_at(v, {-13, 82, 16}), s.hu.cancellous_bone);
  EXPECT_EQ(hu_at(v, {-13, 82 + 29, 16}), s.hu.csf);
  // the volume is centred 20 mm above the heart centre
  EXPECT_NEAR(v.center_mm().z(), 20.0, 1e-9);
}

TEST(ThoraxPhantom, CoronaryLumenFollowsTheTree) {
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({.seed = 3});
  const auto& lad = tree.branches[tree.find("LAD")].points;
  const Eigen::Vector3d p = lad[100].position_m * 1000.0;
  ThoraxPhantomSpec s;
  s.seed = 3;
  s.dims = {24, 24, 24};
  s.spacing_mm = 0.25;
  s.center_mm = p;
  const Volume with = make_thorax_phantom(s, tree);
  EXPECT_EQ(hu_at(with, p), s.contrast_hu);
  // 1 mm beyond the lumen wall: not contrast
  const Eigen::Vector3d out = p + (lad[100].radius_m * 1000.0 + 1.0) * p.normalized();
  EXPECT_NE(hu_at(with, out), s.contrast_hu);
  s.contrast = false;
  EXPECT_EQ(hu_at(make_thorax_phantom(s, tree), p), s.hu.blood);
}

TEST(ThoraxPhantom, LumenInsideTheAortaIsBlood) {
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({.seed = 1});
  // the LM's first point is on the aortic centerline
  const Eigen::Vector3d p = tree.branches[tree.find("LM")].points[2].position_m * 1000.0;
  ThoraxPhantomSpec s;
  s.dims = {16, 16, 16};
  s.spacing_mm = 0.5;
  s.center_mm = p;
  EXPECT_EQ(hu_at(make_thorax_phantom(s, tree), p), s.hu.blood);
}

TEST(ThoraxPhantom, SeededAndIndependentOfThreadCount) {
  ThoraxPhantomSpec s = coarse();
  s.threads = 1;
  const Volume a = make_thorax_phantom(s);
  s.threads = 3;
  const Volume b = make_thorax_phantom(s);
  EXPECT_EQ(a.hu_i16, b.hu_i16);
  s.seed = 2;
  const Volume c = make_thorax_phantom(s);
  EXPECT_NE(a.hu_i16, c.hu_i16);
}

}  // namespace
}  // namespace pcisim::anatomy
