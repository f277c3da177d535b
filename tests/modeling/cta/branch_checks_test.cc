// The crossing check on traced trees with exact geometry (issue #30): a vessel crossing over the
// tree (two arms leaving one point in opposite directions, across it, while it goes on) is cut
// away, also when the trace ran on along the crossing vessel; real branchings are left alone.
#include "modeling/cta/branch_checks.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;
constexpr double kPi = 3.14159265358979323846;

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

// b run on straight from its last sample along `dir` for `length_mm` (samples 0.5 mm apart, radius 1 mm)
ModelBranch then(ModelBranch b, const Vector3d& dir, double length_mm) {
  const ModelBranch on = line(b.points_mm.back(), dir, length_mm);
  b.points_mm.insert(b.points_mm.end(), on.points_mm.begin() + 1, on.points_mm.end());
  b.radius_mm.assign(b.points_mm.size(), 1.0);
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
  const ModelBranch main = then(line({0, 0, 0}, {1, 0, 0}, 20), {0, 1, 0}, 25);  // onto the vein
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
    return then(line({20, 0, 0}, off, 2.0, 0, parent_point), dir, 14);
  };
  ModelTree vein;
  vein.branches.push_back(line({0, 0, 0}, {1, 0, 0}, 40));
  vein.branches.push_back(bent_arm({0, 1, 0}, 40));
  vein.branches.push_back(bent_arm({0, -1, 0}, 40));
  BranchCheckOptions at_the_junction;
  at_the_junction.arm_skip_mm = 0;
  at_the_junction.far_opposite_deg = 181;  // the far window off: never that far apart
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

// a crossing as family seed 2 traced one over OM1: the tracer left the vessel 8 mm before the
// crossing (the vein runs beside it there), followed one vein arm, and left the other arm from
// that arm's second sample. Over 2-6 mm the two arms are ~100 deg apart; over 6-12 mm, on the
// vein itself, 180 deg: cut, with the branch beyond the first arm. The same with a real side
// branch dividing at its second sample (a Y, 80 deg apart) is left alone
TEST(BranchChecks, ACrossingTracedFromBeforeItAndAsAnArmOfAnArmIsCutAway) {
  // from `from` 4 mm on to the vein beside the vessel (at x 24 mm, 1 mm off its axis), then along
  // it (+-y) for 20 mm
  auto onto_vein = [](const Vector3d& from, double side, int parent, int parent_point) {
    const Vector3d to(24, side, 0);
    return then(line(from, to - from, (to - from).norm(), parent, parent_point), {0, side, 0}, 20);
  };
  ModelTree t;
  t.branches.push_back(line({0, 0, 0}, {1, 0, 0}, 40));
  t.branches.push_back(onto_vein({20, 0, 0}, +1, 0, 40));
  t.branches.push_back(onto_vein(t.branches[1].points_mm[1], -1, 1, 1));
  t.branches.push_back(line(t.branches[1].points_mm[20], {0, 0, 1}, 10, 1, 20));  // beyond: goes too
  t.branches.push_back(line({34, 0, 0}, {1, 1, 0}, 10, 0, 68));                   // a real side branch
  BranchCheckOptions near_only;
  near_only.far_opposite_deg = 181;
  ModelTree judged_near = t;
  EXPECT_TRUE(drop_crossings(&judged_near, near_only).empty());
  const auto notes = drop_crossings(&t, BranchCheckOptions{});
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("180 deg"), std::string::npos) << notes[0];
  ASSERT_EQ(t.branches.size(), 2u);
  EXPECT_EQ(t.branches[0].points_mm.size(), 81u);  // the vessel whole
  EXPECT_EQ(t.branches[1].parent_point, 68);       // the side branch kept

  ModelTree y;
  y.branches.push_back(line({0, 0, 0}, {1, 0, 0}, 40));
  y.branches.push_back(line({20, 0, 0}, {0, 1, 0}, 1, 0, 40));
  const Vector3d fork = y.branches[1].points_mm[1];
  ModelBranch left = line(fork, {-0.64, 0.77, 0}, 20, 1, 1);
  left.points_mm.insert(left.points_mm.begin(), y.branches[1].points_mm.front());
  left.radius_mm.push_back(1.0);
  left.parent = 0;
  left.parent_point = 40;
  y.branches[1] = left;                                         // the side branch, on to the left
  y.branches.push_back(line(fork, {0.64, 0.77, 0}, 20, 1, 1));  // its daughter, 80 deg off it
  EXPECT_TRUE(drop_crossings(&y, BranchCheckOptions{}).empty());
  EXPECT_EQ(y.branches.size(), 3u);
}

// the vessel bends where a vein crosses it (family seed 6: D1 turns 48 deg, the vein's arms 64
// and 112 deg off its incoming line): the vessel still goes on, along the arm nearest its line,
// and the crossing is cut. Where a third arm is farther from the line than one of the pair (a
// trifurcation: arms 50 and 130 deg off, the third 55), nothing is
TEST(BranchChecks, AVesselThatBendsAtACrossingStillGoesOn) {
  auto junction = [](double arm_deg, double onward_deg) {
    const double a = arm_deg * kPi / 180, w = onward_deg * kPi / 180;
    ModelTree t;
    t.branches.push_back(line({0, 0, 0}, {1, 0, 0}, 20));
    t.branches.push_back(line({20, 0, 0}, {std::cos(w), 0, std::sin(w)}, 20, 0, 40));  // onwards
    t.branches.push_back(line({20, 0, 0}, {std::cos(a), std::sin(a), 0}, 15, 0, 40));
    t.branches.push_back(line({20, 0, 0}, {-std::cos(a), -std::sin(a), 0}, 15, 0, 40));
    return t;
  };
  ModelTree bend = junction(64, 48);
  ASSERT_EQ(drop_crossings(&bend, BranchCheckOptions{}).size(), 1u);
  ASSERT_EQ(bend.branches.size(), 2u);
  EXPECT_NEAR(bend.branches[1].points_mm.back().z(), 20 * std::sin(48 * kPi / 180), 1e-9);
  ModelTree trifurcation = junction(50, 55);
  EXPECT_TRUE(drop_crossings(&trifurcation, BranchCheckOptions{}).empty());
  EXPECT_EQ(trifurcation.branches.size(), 4u);
}

// a small artery (radius 0.7 mm) that ends against a vein crossing it (radius 1.4): nothing goes
// on, but both arms are twice its width (family seed 20), so they are cut and the vessel ends at
// the junction. A T of daughters narrower than their parent (0.6 mm) is a branching: kept
TEST(BranchChecks, AVesselEndingAgainstAWiderOneIsCutThere) {
  auto tee = [](double arm_radius_mm) {
    ModelTree t;
    t.branches.push_back(line({0, 0, 0}, {1, 0, 0}, 20));
    t.branches.back().radius_mm.assign(t.branches.back().points_mm.size(), 0.7);
    for (double side : {1.0, -1.0}) {
      t.branches.push_back(line({20, 0, 0}, {0, side, 0}, 20, 0, 40));
      t.branches.back().radius_mm.assign(t.branches.back().points_mm.size(), arm_radius_mm);
    }
    return t;
  };
  ModelTree vein = tee(1.4);
  const auto notes = drop_crossings(&vein, BranchCheckOptions{});
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("ends there"), std::string::npos) << notes[0];
  ASSERT_EQ(vein.branches.size(), 1u);
  EXPECT_EQ(vein.branches[0].points_mm.size(), 41u);
  // the vessel's own line ran on along one wide arm: cut back to the junction
  ModelTree ran_on;
  ModelBranch main = then(line({0, 0, 0}, {1, 0, 0}, 20), {0, 1, 0}, 20);
  main.radius_mm.assign(41, 0.7);
  main.radius_mm.resize(main.points_mm.size(), 1.4);
  ran_on.branches.push_back(main);
  ran_on.branches.push_back(line({20, 0, 0}, {0, -1, 0}, 20, 0, 40));
  ran_on.branches.back().radius_mm.assign(ran_on.branches.back().points_mm.size(), 1.4);
  ASSERT_EQ(drop_crossings(&ran_on, BranchCheckOptions{}).size(), 1u);
  ASSERT_EQ(ran_on.branches.size(), 1u);
  EXPECT_EQ(ran_on.branches[0].points_mm.size(), 41u);

  ModelTree branching = tee(0.6);
  EXPECT_TRUE(drop_crossings(&branching, BranchCheckOptions{}).empty());
  EXPECT_EQ(branching.branches.size(), 3u);
}

// the trace ran from the vessel onto the vein, the vessel goes on as a child, and the vein's
// other arm leaves that child at its second sample: the vessel's line is cut back to the
// crossing and the other arm goes, but the child carrying the vessel on stays whole
TEST(BranchChecks, AnArmLeavingTheOnwardVesselGoesAloneNotTheVessel) {
  ModelTree t;
  const ModelBranch main = then(line({0, 0, 0}, {1, 0, 0}, 20), {0, 1, 0}, 25);  // onto the vein
  t.branches.push_back(main);
  t.branches.push_back(line({20, 0, 0}, {1, 0, 0}, 20, 0, 40));                  // the vessel onwards
  t.branches.push_back(line(t.branches[1].points_mm[1], {0, -1, 0}, 15, 1, 1));  // the vein's other arm
  ASSERT_EQ(drop_crossings(&t, BranchCheckOptions{}).size(), 1u);
  ASSERT_EQ(t.branches.size(), 2u);
  EXPECT_EQ(t.branches[0].points_mm.size(), 41u);  // up to the crossing
  EXPECT_EQ(t.branches[1].points_mm.size(), 41u);  // the vessel onwards, whole
  EXPECT_EQ(t.branches[1].parent_point, 40);
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
