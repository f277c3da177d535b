// A wire node's rest point in a moving lumen (rest_point.h). The motion here is the vessel
// skin's in miniature: a vessel of 1.5 mm radius along z moved by D (6 mm sideways) for every
// rest point within the blend radius (4 mm) of its axis, and nothing beyond. A node in the moved
// vessel then has two rest points: its true one inside the vessel, and its own world position
// (beyond every blend, nothing moves it). From a stale guess of no motion (a node just out of a
// catheter in the standing aortic root) the fixed-point steps stop at the wrong one; the
// neighbour's offset finds the true one, which the motion carries.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "physics/guidewire/rest_point.h"

namespace pcisim::physics {
namespace {

constexpr double kCoverM = 0.004;
const Eigen::Vector3d kShift(0.006, 0.0, 0.0);

struct CoveredShift final : LumenMotion {
  // a fraction `a` through the step the shift is a of it (0 at the step's start)
  bool whole_step = true;
  Eigen::Vector3d displacement_m(const Eigen::Vector3d& r, double a) const override {
    if (r.head<2>().norm() > kCoverM) return Eigen::Vector3d::Zero();
    return whole_step ? kShift : Eigen::Vector3d(a * kShift);
  }
  bool carries(const Eigen::Vector3d& r) const override { return r.head<2>().norm() <= kCoverM; }
};

// a smooth motion, a rotation of 0.2 rad about the z axis (|grad d| = 2 sin 0.1 < 1): one rest
// point for every world point
struct SmallTurn final : LumenMotion {
  Eigen::Vector3d displacement_m(const Eigen::Vector3d& r, double) const override {
    return Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()) * r - r;
  }
};

TEST(RestPoint, FromAStaleGuessTheStepsStopAtTheWorldPointThatNothingMoves) {
  const CoveredShift motion;
  const Eigen::Vector3d truth(0.0005, 0.0002, 0.03);
  const Eigen::Vector3d x = truth + kShift;
  // the baseline: a guess of no motion lies beyond the cover, where nothing moves; settled there
  const Eigen::Vector3d stale = rest_point_from(motion, x, x, 1.0);
  EXPECT_LT((stale - x).norm(), 1e-12);
  // and with nothing else to go by, the node's own guess is all there is
  EXPECT_LT((wire_node_rest_point(motion, x, Eigen::Vector3d::Zero(), nullptr, 1.0) - x).norm(), 1e-12);
  // from a guess inside the cover, the true rest point (the one the wire's neighbour gives)
  EXPECT_LT((rest_point_from(motion, x, x - kShift, 1.0) - truth).norm(), 1e-12);
}

TEST(RestPoint, TheNeighboursOffsetChoosesTheRestPointTheWireIsContinuousWith) {
  const CoveredShift motion;
  const Eigen::Vector3d truth(0.0005, 0.0002, 0.03);
  const Eigen::Vector3d x = truth + kShift;
  // the neighbour (1.5 mm nearer the hub) moved with the vessel, nearly as far: the true rest point
  const Eigen::Vector3d moved_neighbour = kShift - Eigen::Vector3d(0.0002, 0.0, 0.0);
  EXPECT_LT((wire_node_rest_point(motion, x, Eigen::Vector3d::Zero(), &moved_neighbour, 1.0) - truth).norm(), 1e-12);
  // the neighbour stands (the catheter in the aortic root) and no guess reaches the vessel: the
  // standing one is all there is
  const Eigen::Vector3d still_neighbour = Eigen::Vector3d::Zero();
  EXPECT_LT((wire_node_rest_point(motion, x, Eigen::Vector3d::Zero(), &still_neighbour, 1.0) - x).norm(), 1e-12);
  // the neighbour half way (2.9 mm): the standing answer's offset is nearer it (2.9 mm against
  // 3.1), but the vessel carries the other, and a node in a vessel moves with it
  const Eigen::Vector3d half_neighbour(0.0029, 0.0, 0.0);
  EXPECT_LT((wire_node_rest_point(motion, x, Eigen::Vector3d::Zero(), &half_neighbour, 1.0) - truth).norm(), 1e-12);
  // a node whose own guess is right keeps it while the neighbour's offset is near its own
  EXPECT_LT((wire_node_rest_point(motion, x, kShift, &moved_neighbour, 1.0) - truth).norm(), 1e-12);
}

TEST(RestPoint, PartWayThroughTheStepTheNodeIsCarriedByThatFractionOfTheMotion) {
  CoveredShift motion;
  motion.whole_step = false;
  const Eigen::Vector3d truth(0.0003, 0.0011, 0.01);
  // far enough through the step that the vessel has left its own reach (a shift over 3.7 mm)
  for (double a : {0.7, 0.85, 1.0}) {
    const Eigen::Vector3d x = truth + a * kShift;
    EXPECT_LT((rest_point_from(motion, x, x, a) - x).norm(), 1e-12) << a << ": the stale guess stops at x";
    const Eigen::Vector3d neighbour = a * kShift;
    EXPECT_LT((wire_node_rest_point(motion, x, Eigen::Vector3d::Zero(), &neighbour, a) - truth).norm(), 1e-12) << a;
  }
}

// two vessels within reach of one world point: the first (at the origin) moved 6 mm towards the
// second (at x = 10 mm), which stands still. A point of the moved first vessel lies within the
// second's reach too, so both answers are fixed points the motion carries: the neighbour's offset
// decides (the wire is continuous)
struct TwoVessels final : LumenMotion {
  static bool near_second(const Eigen::Vector3d& r) {
    return (r.head<2>() - Eigen::Vector2d(0.01, 0.0)).norm() <= kCoverM;
  }
  Eigen::Vector3d displacement_m(const Eigen::Vector3d& r, double) const override {
    return r.head<2>().norm() <= kCoverM ? kShift : Eigen::Vector3d::Zero();
  }
  bool carries(const Eigen::Vector3d& r) const override { return r.head<2>().norm() <= kCoverM || near_second(r); }
};

TEST(RestPoint, WhereTwoVesselsReachThePointTheNeighbourDecides) {
  const TwoVessels motion;
  const Eigen::Vector3d truth(0.0005, 0.0002, 0.03);
  const Eigen::Vector3d x = truth + kShift;  // 3.5 mm from the second vessel's axis
  ASSERT_TRUE(TwoVessels::near_second(x));
  const Eigen::Vector3d moved_neighbour = kShift - Eigen::Vector3d(0.0001, 0.0, 0.0);
  const Eigen::Vector3d still_neighbour = Eigen::Vector3d::Zero();
  // from the stale guess the node stops at x (carried by the second vessel, standing); its
  // neighbour moved with the first vessel: so did the node
  EXPECT_LT((wire_node_rest_point(motion, x, Eigen::Vector3d::Zero(), &moved_neighbour, 1.0) - truth).norm(), 1e-12);
  // its neighbour stands in the second vessel: so does the node, whatever its own guess
  EXPECT_LT((wire_node_rest_point(motion, x, kShift, &still_neighbour, 1.0) - x).norm(), 1e-12);
}

TEST(RestPoint, WhereTheMotionIsSmoothTheNeighbourChangesNothing) {
  const SmallTurn motion;
  const Eigen::Vector3d truth(0.004, -0.002, 0.02);
  const Eigen::Vector3d x = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()) * truth;
  const Eigen::Vector3d offset = x - truth;
  // from the node's own last offset, a little stale, and a neighbour's far off: the one answer
  const Eigen::Vector3d far_neighbour(0.003, 0.0, 0.0);
  const Eigen::Vector3d own = 0.9 * offset;
  const Eigen::Vector3d alone = rest_point_from(motion, x, x - own, 1.0);
  const Eigen::Vector3d with = wire_node_rest_point(motion, x, own, &far_neighbour, 1.0);
  // (each fixed-point step contracts by |grad d| ~ 0.2: within 1 um of the truth)
  EXPECT_LT((alone - truth).norm(), 1e-6);
  EXPECT_LT((with - truth).norm(), 1e-6);
}

}  // namespace
}  // namespace pcisim::physics
