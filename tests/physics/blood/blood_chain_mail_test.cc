// Pulsatile blood as chain-mails along the coronary centerlines and its pull on the wire (eq 12).
#include "physics/blood/blood_chain_mail.h"

#include <gtest/gtest.h>

#include <cmath>

#include "physics/guidewire/catheter_path.h"
#include "physics/vessel/coronary_phantom.h"
#include "tests/common/counting_new.h"

namespace pcisim::physics {
namespace {

TEST(BloodFlowWaveform, MeanIsOneSystoleIsThrottledDiastoleCarriesTheRest) {
  for (double p : {0.0, 0.4, 0.8}) {
    double mean = 0.0;
    const int n = 100000;
    for (int k = 0; k < n; ++k) mean += coronary_flow_fraction((k + 0.5) / n, p);
    EXPECT_NEAR(mean / n, 1.0, 1e-6) << p;
    EXPECT_DOUBLE_EQ(coronary_flow_fraction(0.1, p), 1.0 - p);
    EXPECT_GE(coronary_flow_fraction(0.6, p), 1.0) << p;
  }
  // periodic
  EXPECT_DOUBLE_EQ(coronary_flow_fraction(1.6, 0.4), coronary_flow_fraction(0.6, 0.4));
  EXPECT_DOUBLE_EQ(coronary_flow_fraction(-0.4, 0.4), coronary_flow_fraction(0.6, 0.4));
}

class BloodChainMailTest : public ::testing::Test {
 protected:
  VesselTree tree = make_coronary_phantom({1});
  BloodFlowParams params;
};

TEST_F(BloodChainMailTest, ProfileIsParabolicAndFlowsDownstream) {
  params.pulsatility = 0.0;
  BloodChainMail blood(params, tree);
  ASSERT_GT(blood.cell_count(), 1000);
  const auto pos = blood.cell_positions_m();
  const auto vel = blood.cell_velocities_m_per_s();
  const double mean = params.mean_velocity_m_per_s;
  int axis = 0, ring = 0;
  for (int c = 0; c < blood.cell_count(); ++c) {
    double dist = 0.0;
    const int b = nearest_branch(tree, pos[c], &dist);
    ASSERT_GE(b, 0);
    const double speed = vel[c].norm();
    // Poiseuille: 2 x mean on the axis, 2 (1 - 0.6^2) x mean on the ring at 0.6 R
    if (std::abs(speed - 2.0 * mean) < 1e-9) ++axis;
    else if (std::abs(speed - 1.28 * mean) < 1e-9) ++ring;
    else ADD_FAILURE() << "cell " << c << " speed " << speed;
  }
  EXPECT_EQ(ring, 6 * axis);
  // along the LAD the velocity points distally
  const auto& lad = tree.branches[tree.find("LAD")].points;
  const size_t k = lad.size() / 2;
  const Eigen::Vector3d along = (lad[k + 1].position_m - lad[k - 1].position_m).normalized();
  const Eigen::Vector3d v = blood.linked_velocity(lad[k].position_m);
  EXPECT_GT(v.dot(along), 1.2 * mean);
  EXPECT_LT(v.norm(), 2.0 * mean + 1e-12);
  EXPECT_EQ(blood.linked_velocity(Eigen::Vector3d(0.3, 0.3, 0.3)), Eigen::Vector3d::Zero());
  EXPECT_EQ(blood.linked_velocity(Eigen::Vector3d(std::nan(""), 0, 0)), Eigen::Vector3d::Zero());
}

TEST_F(BloodChainMailTest, FlowFollowsTheCardiacCycle) {
  BloodChainMail blood(params, tree);
  const auto& lad = tree.branches[tree.find("LAD")].points;
  const Eigen::Vector3d p = lad[lad.size() / 2].position_m;
  const double expected = coronary_flow_fraction(0.6, params.pulsatility) / (1.0 - params.pulsatility);
  blood.step(1e-4, 0.1);  // systole
  const double systolic = blood.linked_velocity(p).norm();
  const double cell_systolic = blood.cell_velocities_m_per_s()[0].norm();
  blood.step(1e-4, 0.6);  // early diastole
  const double diastolic = blood.linked_velocity(p).norm();
  // every chain-mail's speed scales with the flow rate exactly; the blend at p nearly so (the
  // chain-mails have moved a little, changing their weights)
  EXPECT_NEAR(blood.cell_velocities_m_per_s()[0].norm() / cell_systolic, expected, 1e-9);
  EXPECT_NEAR(diastolic / systolic, expected, 0.1 * expected);
  EXPECT_GT(diastolic, 2.0 * systolic);
}

TEST_F(BloodChainMailTest, CellsAdvanceByTheirVelocityAndRecirculate) {
  params.pulsatility = 0.0;
  BloodChainMail blood(params, tree);
  const std::vector<Eigen::Vector3d> before(blood.cell_positions_m().begin(), blood.cell_positions_m().end());
  const std::vector<Eigen::Vector3d> v0(blood.cell_velocities_m_per_s().begin(), blood.cell_velocities_m_per_s().end());
  const double dt = 1e-3;
  blood.step(dt, 0.0);
  int moved_as_expected = 0;
  for (int c = 0; c < blood.cell_count(); ++c) {
    const double d = (blood.cell_positions_m()[c] - before[c] - v0[c] * dt).norm();
    if (d < 0.15 * v0[c].norm() * dt + 1e-9) ++moved_as_expected;  // along the tangent, except at bends and the wrap
  }
  EXPECT_GT(moved_as_expected, 0.95 * blood.cell_count());
  // a long run keeps every cell inside its vessel
  for (int k = 0; k < 300; ++k) blood.step(1.0 / 30, k / 25.0);
  for (int c = 0; c < blood.cell_count(); c += 7) {
    double dist = 0.0;
    const int b = nearest_branch(tree, blood.cell_positions_m()[c], &dist);
    ASSERT_GE(b, 0);
    EXPECT_LT(dist, 0.0021) << c;
  }
}

TEST_F(BloodChainMailTest, WireFreeNodesTakeTheWeightedBloodVelocity) {
  BloodChainMail blood(params, tree);
  blood.step(1.0 / 30, 0.6);
  ChainMailWire wire(GuidewireParams{}, CatheterPath(guide_catheter_path(tree)));
  wire.begin_step(0.010, 0.0);
  wire.restore_limits();
  const std::vector<Eigen::Vector3d> before(wire.nodes_m().begin(), wire.nodes_m().end());
  const double dt = 1.0 / 30.0;
  blood.apply(wire, dt);
  const auto after = wire.nodes_m();
  for (int i = 0; i < wire.node_count(); ++i) {
    const Eigen::Vector3d expected = i >= wire.first_free_node()
                                         ? Eigen::Vector3d(params.drift_gain * dt * blood.linked_velocity(before[i]))
                                         : Eigen::Vector3d::Zero();
    EXPECT_LT((after[i] - before[i] - expected).norm(), 1e-12) << i;
  }
  EXPECT_GT((after.back() - before.back()).norm(), 0.0);  // the tip is in the LM's flow
}

TEST_F(BloodChainMailTest, StepAndApplyAllocateNothing) {
  BloodChainMail blood(params, tree);
  ChainMailWire wire(GuidewireParams{}, CatheterPath(guide_catheter_path(tree)));
  wire.begin_step(0.010, 0.0);
  wire.restore_limits();
  long n = -1;
  {
    pcisim::testing::AllocationCount count;
    for (int k = 0; k < 10; ++k) {
      blood.step(1.0 / 30, 0.1 * k);
      blood.apply(wire, 1.0 / 30);
    }
    n = count.allocations();
  }
  EXPECT_EQ(n, 0);
}

}  // namespace
}  // namespace pcisim::physics
