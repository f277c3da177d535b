// Blood flow on the wire (eq 12): a steady flow along the centerlines, proximal to distal,
// at the scene's mean velocity; nothing outside the vessels; free nodes drift with a fraction of it.
#include "physics/guidewire/blood_drift.h"

#include <gtest/gtest.h>

#include "physics/vessel/coronary_phantom.h"

namespace pcisim::physics {
namespace {

TEST(BloodDrift, FlowsDownEveryBranchAtTheMeanVelocity) {
  const VesselTree tree = make_coronary_phantom({1});
  BloodFlowParams p;
  const BloodDrift drift(p, tree);
  for (const char* name : {"LM", "LAD", "LCx", "RCA"}) {
    const auto& pts = tree.branches[tree.find(name)].points;
    const size_t k = pts.size() / 2;
    const Eigen::Vector3d along = (pts[k + 1].position_m - pts[k - 1].position_m).normalized();
    const Eigen::Vector3d v = drift.velocity(pts[k].position_m);
    EXPECT_GT(v.dot(along), 0.9 * p.mean_velocity_m_per_s) << name;
    EXPECT_LT(v.norm(), 1.05 * p.mean_velocity_m_per_s) << name;
  }
  EXPECT_EQ(drift.velocity(Eigen::Vector3d(0.5, 0.5, 0.5)), Eigen::Vector3d::Zero());
  EXPECT_EQ(drift.velocity(Eigen::Vector3d(std::nan(""), 0.0, 0.0)), Eigen::Vector3d::Zero());
}

TEST(BloodDrift, MovesOnlyFreeNodesByGainTimesFlowTimesStep) {
  const VesselTree tree = make_coronary_phantom({1});
  BloodFlowParams p;
  const BloodDrift drift(p, tree);
  ChainMailWire wire(GuidewireParams{}, CatheterPath(guide_catheter_path(tree)));
  wire.begin_step(0.010, 0.0);
  wire.restore_limits();
  const std::vector<Eigen::Vector3d> before(wire.nodes_m().begin(), wire.nodes_m().end());
  const double dt = 1.0 / 30.0;
  drift.apply(wire, dt);
  const auto after = wire.nodes_m();
  for (int i = 0; i < wire.node_count(); ++i) {
    const Eigen::Vector3d expected =
        i >= wire.first_free_node() ? Eigen::Vector3d(p.drift_gain * dt * drift.velocity(before[i])) : Eigen::Vector3d::Zero();
    EXPECT_LT((after[i] - before[i] - expected).norm(), 1e-12) << i;
  }
  EXPECT_GT((after.back() - before.back()).norm(), 0.0);  // the tip is in the LM's flow
}

}  // namespace
}  // namespace pcisim::physics
