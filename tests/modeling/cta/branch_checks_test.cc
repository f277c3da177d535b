// The crossing check on traced trees with exact geometry (issue #30): a vessel crossing over the
// tree (two arms leaving one point in opposite directions, across it, while it goes on) is cut
// away, also when the trace ran on along the crossing vessel; real branchings are left alone.
#include "modeling/cta/branch_checks.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

// a straight branch from `from` along `dir` for `length_mm`, samples 0.5 mm apart, radius 1 mm
ModelBranch line(const Vector3d& from, const Vector3d& dir, double length_mm, int parent = -1, int parent_point = -1) {
  ModelBranch b;
  for (double s = 0; s <= length_mm + 1e-9; s += 0.5) {
    b.points_mm.push_back(from + s * dir.normalized());
    b.radius_mm.push_back(1.0);
  }
  b.parent = parent;
  b.parent_point = parent_point;
  return b;
}

// the vessel along x, 40 mm; at 20 mm (sample 40) a vein crosses it along y
TEST(BranchChecks, AVesselCrossingOverTheTreeIsCutAway) {
  ModelTree t;
  t.branches.push_back(line({0, 0, 0}, {1, 0, 0}, 40));
  t.branches.push_back(line({20, 0, 0}, {0, 1, 0}, 15, 0, 40));
  t.branches.push_back(line({20, 0, 0}, {0, -1, 0.1}, 18, 0, 41));
  t.branches.push_back(line({30, 0, 0}, {1, 1, 0}, 10, 0, 60));  // a real side branch further on
  const auto notes = drop_crossings(&t, BranchCheckOptions{});
  ASSERT_EQ(notes.size(), 1u) << (notes.empty() ? "" : notes[0]);
  EXPECT_NE(notes[0].find("crossing"), std::string::npos);
  ASSERT_EQ(t.branches.size(), 2u);
  EXPECT_EQ(t.branches[0].points_mm.size(), 81u);  // the vessel whole
  EXPECT_EQ(t.branches[1].parent, 0);
  EXPECT_EQ(t.branches[1].parent_point, 60);  // the side branch kept, re-indexed
}

// the trace ran from the vessel onto the crossing vein (its own line turns at the crossing) and
// the vessel's onward part is a child: the line is cut back to the crossing, the vein's other arm
// goes, the onward vessel stays
TEST(BranchChecks, ACrossingTheTraceRanOntoIsCutBackToTheVessel) {
  ModelTree t;
  ModelBranch main = line({0, 0, 0}, {1, 0, 0}, 20);
  const ModelBranch vein_arm = line({20, 0, 0}, {0, 1, 0}, 25);
  main.points_mm.insert(main.points_mm.end(), vein_arm.points_mm.begin() + 1, vein_arm.points_mm.end());
  main.radius_mm.assign(main.points_mm.size(), 1.0);
  t.branches.push_back(main);
  t.branches.push_back(line({20, 0, 0}, {1, 0, 0}, 20, 0, 40));   // the vessel onwards
  t.branches.push_back(line({20, 0, 0}, {0, -1, 0}, 15, 0, 40));  // the vein's other arm
  ModelTree later = t;  // the same, the onward vessel leaving two samples (1 mm) past the crossing
  later.branches[1] = line(main.points_mm[42], {1, 0, 0}, 19, 0, 42);
  const auto notes = drop_crossings(&t, BranchCheckOptions{});
  ASSERT_EQ(notes.size(), 1u);
  ASSERT_EQ(t.branches.size(), 2u);
  EXPECT_EQ(t.branches[0].points_mm.size(), 41u);  // up to the crossing
  EXPECT_NEAR(t.branches[1].points_mm.back().x(), 40.0, 1e-9);
  EXPECT_EQ(t.branches[1].parent, 0);
  // a side branch leaving 1 mm before the crossing, 15 deg off the vein's other arm: no second
  // pair with the vessel's line once that is cut back (it was judged against the line as it was)
  ModelTree with_side = later;
  const Vector3d side_dir(std::sin(0.26), -std::cos(0.26), 0);
  with_side.branches.push_back(line({19, 0, 0}, side_dir, 15, 0, 38));
  ASSERT_EQ(drop_crossings(&with_side, BranchCheckOptions{}).size(), 1u);
  ASSERT_EQ(with_side.branches.size(), 3u);
  EXPECT_EQ(with_side.branches[2].parent_point, 38);
  // the cut keeps the sample the onward vessel leaves from: it stays, whole
  ASSERT_EQ(drop_crossings(&later, BranchCheckOptions{}).size(), 1u);
  ASSERT_EQ(later.branches.size(), 2u);
  EXPECT_EQ(later.branches[0].points_mm.size(), 43u);
  EXPECT_EQ(later.branches[1].parent_point, 42);
}

// a crossing as the tracer leaves it: each vein arm bends through the junction's blob of lumen
// over its first 2 mm (there 55 deg off its course: over 4 mm from the junction the two arms are
// 125 deg apart, under the 130 that makes a pair opposite); judged past that bend, 180 deg apart,
// and cut. A side branch (D) leaves the vessel 1 mm before the crossing, 15 deg off one vein arm's
// course: with the other arm it is a pair too, but the vein's is the more nearly opposite, and D
// stays
TEST(BranchChecks, ACrossingIsJudgedPastTheJunctionsBendAndTakesItsMostOppositePair) {
  // an arm leaving (20, 0, 0): its first 2 mm at 55 deg off `dir` towards +x, then along dir
  auto bent_arm = [](const Vector3d& dir, int parent_point) {
    const Vector3d off = std::cos(0.96) * dir + std::sin(0.96) * Vector3d::UnitX();
    ModelBranch b = line({20, 0, 0}, off, 2.0, 0, parent_point);
    const ModelBranch on = line(b.points_mm.back(), dir, 14);
    b.points_mm.insert(b.points_mm.end(), on.points_mm.begin() + 1, on.points_mm.end());
    b.radius_mm.assign(b.points_mm.size(), 1.0);
    return b;
  };
  ModelTree vein;
  vein.branches.push_back(line({0, 0, 0}, {1, 0, 0}, 40));
  vein.branches.push_back(bent_arm({0, 1, 0}, 40));
  vein.branches.push_back(bent_arm({0, -1, 0}, 40));
  BranchCheckOptions at_the_junction;
  at_the_junction.arm_skip_mm = 0;
  ModelTree unskipped = vein;
  EXPECT_TRUE(drop_crossings(&unskipped, at_the_junction).empty());
  ModelTree t = vein;
  const Vector3d d_dir(std::sin(0.26), -std::cos(0.26), 0);  // 15 deg off the lower arm, towards +x
  t.branches.push_back(line({19, 0, 0}, d_dir, 15, 0, 38));  // D
  EXPECT_EQ(drop_crossings(&vein, BranchCheckOptions{}).size(), 1u);
  EXPECT_EQ(vein.branches.size(), 1u);
  const auto notes = drop_crossings(&t, BranchCheckOptions{});
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("180 deg"), std::string::npos) << notes[0];
  ASSERT_EQ(t.branches.size(), 2u);
  EXPECT_EQ(t.branches[1].parent_point, 38);  // D
}

// what is not a crossing: a bifurcation (the vessel ends in two daughters 80 deg apart), two side
// branches leaving one point 90 deg apart (a diagonal and a septal), and opposite arms where the
// vessel does not go on
TEST(BranchChecks, BranchingsAreNotCrossings) {
  ModelTree fork;
  fork.branches.push_back(line({0, 0, 0}, {1, 0, 0}, 20));
  fork.branches.push_back(line({20, 0, 0}, {1, 0.84, 0}, 20, 0, 40));
  fork.branches.push_back(line({20, 0, 0}, {1, -0.84, 0}, 20, 0, 40));
  EXPECT_TRUE(drop_crossings(&fork, BranchCheckOptions{}).empty());
  EXPECT_EQ(fork.branches.size(), 3u);

  ModelTree sides;
  sides.branches.push_back(line({0, 0, 0}, {1, 0, 0}, 40));
  sides.branches.push_back(line({20, 0, 0}, {0, 1, 0}, 15, 0, 40));
  sides.branches.push_back(line({20, 0, 0}, {0, 0, -1}, 15, 0, 40));
  EXPECT_TRUE(drop_crossings(&sides, BranchCheckOptions{}).empty());
  EXPECT_EQ(sides.branches.size(), 3u);

  ModelTree tee;  // the vessel ends in a T: nothing carries it on
  tee.branches.push_back(line({0, 0, 0}, {1, 0, 0}, 20));
  tee.branches.push_back(line({20, 0, 0}, {0, 1, 0}, 15, 0, 40));
  tee.branches.push_back(line({20, 0, 0}, {0, -1, 0}, 15, 0, 40));
  EXPECT_TRUE(drop_crossings(&tee, BranchCheckOptions{}).empty());
  EXPECT_EQ(tee.branches.size(), 3u);
}

// a vein beside the vessel, touching it (centres 2.2 mm apart): traced as a branch that leaves
// the vessel and runs back along it for 20 mm; it is cut away. A real side branch leaving at
// 45 deg, a short branch that starts beside the vessel, and an 8 mm branch leaving at 30 deg
// (near its parent for most of its length, but not along it) are left alone
TEST(BranchChecks, AVesselBesideItsParentIsCutAwayAndRealBranchesAreNot) {
  ModelTree t;
  t.branches.push_back(line({0, 0, 0}, {1, 0, 0}, 60));
  ModelBranch vein = line({30, 0, 0}, {0, 1, 0}, 2.2, 0, 60);  // over to the vein
  const ModelBranch along = line({30, 2.2, 0}, {-1, 0, 0}, 20);
  vein.points_mm.insert(vein.points_mm.end(), along.points_mm.begin() + 1, along.points_mm.end());
  vein.radius_mm.assign(vein.points_mm.size(), 1.0);
  t.branches.push_back(vein);
  t.branches.push_back(line({45, 0, 0}, {1, 1, 0}, 15, 0, 90));    // a side branch at 45 deg
  t.branches.push_back(line({50, 0, 0}, {1, 0.3, 0}, 6, 0, 100));  // short, beside at first
  // an 8 mm branch of 1 mm leaving at 30 deg a parent of 1.75 mm: near it for most of its length
  ModelBranch shallow = line({55, 0, 0}, {std::cos(0.52), std::sin(0.52), 0}, 8, 0, 110);
  t.branches.push_back(shallow);
  for (double& r : t.branches[0].radius_mm) r = 1.75;
  const auto notes = drop_parallel_branches(&t, BranchCheckOptions{});
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("beside"), std::string::npos) << notes[0];
  ASSERT_EQ(t.branches.size(), 4u);
  EXPECT_EQ(t.branches[1].parent_point, 90);
  EXPECT_EQ(t.branches[2].parent_point, 100);
  EXPECT_EQ(t.branches[3].parent_point, 110);
}

}  // namespace
}  // namespace pcisim::modeling
