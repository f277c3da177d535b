// innermost_branch: the lumen that holds a point, radius counted, where nearest_branch goes by
// centerline distance alone and calls the aortic wall beside the left main's first points "LM".
#include <gtest/gtest.h>

#include <cmath>

#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::anatomy {
namespace {

// an aorta (radius 15 mm) along z and a left main (radius 2 mm) leaving its centerline along x
VesselTree aorta_and_lm() {
  VesselTree t;
  VesselBranch aorta{"aorta", -1, -1, {}};
  for (int k = 0; k <= 10; ++k) aorta.points.push_back({Eigen::Vector3d(0, 0, 0.01 * (k - 5)), 0.015});
  VesselBranch lm{"LM", 0, 5, {}};
  for (int k = 0; k <= 20; ++k) lm.points.push_back({Eigen::Vector3d(0.002 * k, 0, 0), 0.002});
  t.branches = {aorta, lm};
  return t;
}

TEST(InnermostBranch, TheAorticWallBesideTheLeftMainsStubIsTheAorta) {
  const VesselTree t = aorta_and_lm();
  // 12 mm out, 5 mm off the LM's line: 13 mm from the aorta's axis (2 mm inside it), 3 mm
  // outside the LM's tube
  const Eigen::Vector3d wall(0.012, 0.005, 0.0);
  EXPECT_EQ(nearest_branch(t, wall), 1);  // the centerline alone says LM
  double depth = 0;
  EXPECT_EQ(innermost_branch(t, wall, &depth), 0);
  EXPECT_NEAR(depth, std::hypot(0.012, 0.005) - 0.015, 1e-12);
}

TEST(InnermostBranch, APointInTheLeftMainBeyondTheAortaIsTheLeftMain) {
  const VesselTree t = aorta_and_lm();
  double depth = 0;
  EXPECT_EQ(innermost_branch(t, Eigen::Vector3d(0.020, 0.0005, 0.0), &depth), 1);
  EXPECT_NEAR(depth, 0.0005 - 0.002, 1e-12);
  // outside every lumen: the one it is least outside of, with a positive depth
  EXPECT_EQ(innermost_branch(t, Eigen::Vector3d(0.030, 0.004, 0.0), &depth), 1);
  EXPECT_NEAR(depth, 0.002, 1e-12);
  // nothing to hold it
  EXPECT_EQ(innermost_branch(VesselTree{}, Eigen::Vector3d::Zero()), -1);
  EXPECT_EQ(innermost_branch(t, Eigen::Vector3d(NAN, 0, 0)), -1);
}

}  // namespace
}  // namespace pcisim::anatomy
