// Pulsatile blood as chain-mails along the coronary centerlines and its pull on the wire (eq 12).
#include "physics/blood/blood_chain_mail.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <tuple>

#include "physics/guidewire/catheter_path.h"
#include "anatomy/phantom/coronary_phantom.h"
#include "realtime/allocation_count.h"

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
  anatomy::VesselTree tree = anatomy::make_coronary_phantom({1});
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
    const int b = anatomy::nearest_branch(tree, pos[c], &dist);
    ASSERT_GE(b, 0);
    const double speed = vel[c].norm();
    // Poiseuille: 2 x mean on the axis, 2 (1 - 0.6^2) x mean on the ring at 0.6 R
    if (std::abs(speed - 2.0 * mean) < 1e-9)
      ++axis;
    else if (std::abs(speed - 1.28 * mean) < 1e-9)
      ++ring;
    else
      ADD_FAILURE() << "cell " << c << " speed " << speed;
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
    const int b = anatomy::nearest_branch(tree, blood.cell_positions_m()[c], &dist);
    ASSERT_GE(b, 0);
    EXPECT_LT(dist, 0.0021) << c;
  }
}

TEST_F(BloodChainMailTest, WireFreeNodesTakeTheWeightedBloodVelocity) {
  BloodChainMail blood(params, tree);
  blood.step(1.0 / 30, 0.6);
  ChainMailWire wire(GuidewireParams{}, CatheterPath(anatomy::guide_catheter_path(tree)));
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

// two straight vessels 3 mm apart, flowing opposite ways: eq 12 by hand (inverse-distance weights
// over the chain-mails within the link radius, of the nearest vessel only) against linked_velocity
TEST(BloodChainMailLinks, NearestVesselsChainMailsBlendedByInverseDistance) {
  anatomy::VesselTree t;
  for (const auto& [name, y, dir] : {std::tuple{"A", 0.0, 1.0}, std::tuple{"B", 3e-3, -1.0}}) {
    anatomy::VesselBranch b;
    b.name = name;
    for (int k = 0; k <= 40; ++k)
      b.points.push_back({Eigen::Vector3d(dir * 0.5e-3 * k + (dir < 0 ? 20e-3 : 0.0), y, 0), 1e-3});
    t.branches.push_back(b);
  }
  BloodFlowParams p;
  p.link_radius_m = 2.5e-3;
  BloodChainMail blood(p, t);
  blood.step(1.0 / 30, 0.6);
  const auto pos = blood.cell_positions_m();
  const auto vel = blood.cell_velocities_m_per_s();
  // by hand: which vessel a chain-mail is in from its y; the nearest chain-mail picks the vessel
  auto by_hand = [&](const Eigen::Vector3d& q) {
    int vessel = -1;
    double nearest = p.link_radius_m;
    for (int c = 0; c < blood.cell_count(); ++c)
      if ((pos[c] - q).norm() <= nearest) {
        nearest = (pos[c] - q).norm();
        vessel = pos[c].y() < 1.5e-3 ? 0 : 1;
      }
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double wsum = 0;
    for (int c = 0; c < blood.cell_count(); ++c) {
      const double d = (pos[c] - q).norm();
      if (d > p.link_radius_m || (pos[c].y() < 1.5e-3 ? 0 : 1) != vessel) continue;
      const double w = 1.0 / (d + 0.25 * p.cell_spacing_m);
      sum += w * vel[c];
      wsum += w;
    }
    return wsum > 0 ? Eigen::Vector3d(sum / wsum) : Eigen::Vector3d::Zero();
  };
  const Eigen::Vector3d near_a(10.2e-3, 1.2e-3, 0.1e-3), near_b(10.2e-3, 1.8e-3, 0.1e-3), away(10e-3, 1.5e-3, 6e-3);
  EXPECT_LT((blood.linked_velocity(near_a) - by_hand(near_a)).norm(), 1e-12);
  EXPECT_LT((blood.linked_velocity(near_b) - by_hand(near_b)).norm(), 1e-12);
  EXPECT_GT(blood.linked_velocity(near_a).x(), 0.1) << "A's flow alone, not averaged with B's opposite one";
  EXPECT_LT(blood.linked_velocity(near_b).x(), -0.1) << "B's flow alone";
  EXPECT_EQ(blood.linked_velocity(away), Eigen::Vector3d::Zero()) << "no blood within reach";
  // nearer chain-mails weigh more: on A's axis the blend is faster than the plain mean of the same
  // chain-mails (the near ones are the fast axis ones, the ring ones are slower and farther)
  const Eigen::Vector3d axis_point(10.0e-3, 0, 0);
  double plain = 0;
  int linked = 0;
  for (int c = 0; c < blood.cell_count(); ++c)
    if ((pos[c] - axis_point).norm() <= p.link_radius_m && pos[c].y() < 1.5e-3) {
      plain += vel[c].x();
      ++linked;
    }
  ASSERT_GT(linked, 10);
  EXPECT_GT(blood.linked_velocity(axis_point).x(), plain / linked + 1e-3);
}

TEST(BloodChainMailLinks, BadParametersAreRefusedByName) {
  const anatomy::VesselTree t = anatomy::make_coronary_phantom({1});
  for (auto [field, bad] : {std::pair{"blood_flow.cell_spacing_m", 0.0}, std::pair{"blood_flow.link_radius_m", 0.0}}) {
    BloodFlowParams p;
    (std::string(field).find("cell") != std::string::npos ? p.cell_spacing_m : p.link_radius_m) = bad;
    try {
      BloodChainMail b(p, t);
      FAIL() << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(field, 0), 0u) << e.what();
    }
  }
}

TEST_F(BloodChainMailTest, StepAndApplyAllocateNothing) {
  BloodChainMail blood(params, tree);
  ChainMailWire wire(GuidewireParams{}, CatheterPath(anatomy::guide_catheter_path(tree)));
  wire.begin_step(0.010, 0.0);
  wire.restore_limits();
  long n = -1;
  {
    pcisim::realtime::AllocationCount count;
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
