// The rod's contact compliance W = H A^-1 H^T (issue #33) against Euler-Bernoulli beam theory:
// over a long substep the nodes' inertia vanishes next to h^2 K, so h^2 W is the static
// compliance of the clamped beam (tip: L^3 / 3EI; a node at x under a tip load:
// x^2 (3L - x) / 6EI; axially L / EA); over a very short one W is the inverse node mass. The
// response to impulses moves the nodes by W L and loads the clamp with the applied force.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <array>
#include <utility>
#include <cmath>
#include <cstdio>
#include <vector>

#include "physics/rod/unit_cantilever.h"

namespace pcisim::physics::rod {
namespace {

constexpr int kSegments = 20;

// a hook that, after the rod's (only) solve of the substep, takes W for `nodes` and optionally
// applies impulses to them
class ComplianceProbe final : public RodContact {
 public:
  explicit ComplianceProbe(std::vector<int> nodes)
      : nodes_(std::move(nodes)), w_(3 * nodes_.size(), 3 * nodes_.size()) {}
  void project(CosseratRod& rod, int /*iteration*/, double /*h*/) override {
    ok_ = rod.contact_compliance(nodes_, w_);
    if (!impulses_.empty()) {
      before_.assign(rod.nodes_m().begin(), rod.nodes_m().end());
      applied_ = rod.apply_contact_impulses(nodes_, impulses_);
    }
  }
  std::vector<int> nodes_;
  Eigen::MatrixXd w_;
  std::vector<Eigen::Vector3d> impulses_, before_;
  bool ok_ = false, applied_ = false;
};

CosseratRodParams straight_rod() {
  CosseratRodParams p = unit_cantilever(kSegments);
  p.gravity_m_per_s2.setZero();
  p.substeps = 1;
  p.max_substep_s = 1e9;  // one substep of whatever step is asked
  p.iterations = 1;
  return p;
}

// y is lateral (the clamp points along x), x axial: W's entry for node a's axis da and node b's axis db
double entry(const Eigen::MatrixXd& w, int a, int da, int b, int db) {
  return w(3 * a + da, 3 * b + db);
}

TEST(RodContactCompliance, OverALongSubstepIsTheClampedBeamsStaticCompliance) {
  const CosseratRodParams p = straight_rod();
  CosseratRod rod = make_unit_cantilever(p);
  const int mid = kSegments / 2, tip = kSegments;
  ComplianceProbe probe({mid, tip});
  const double h = 100.0;  // m / (h^2 K) ~ 1e-6
  rod.step(h, &probe);
  ASSERT_TRUE(probe.ok_);
  const Eigen::MatrixXd c = h * h * probe.w_;  // m per N
  const double ei = p.bending_stiffness_nm2, ea = p.axial_stiffness_n, l = p.length_m, x = 0.5 * l;
  const double tip_lateral = l * l * l / (3.0 * ei);
  const double mid_under_tip_load = x * x * (3.0 * l - x) / (6.0 * ei);
  const double mid_lateral = x * x * x / (3.0 * ei);
  std::printf("h^2 W: tip %.6f (beam %.6f), mid under tip %.6f (beam %.6f), mid %.6f (beam %.6f), axial %.4g (%.4g)\n",
              entry(c, 1, 1, 1, 1), tip_lateral, entry(c, 0, 1, 1, 1), mid_under_tip_load, entry(c, 0, 1, 0, 1),
              mid_lateral, entry(c, 1, 0, 1, 0), l / ea);
  // measured at 20 segments: 0.12 % (tip), 0.2 % and 0.5 % (mid); the discretisation's, falling
  // as 1 / N^2 (the next test)
  EXPECT_NEAR(entry(c, 1, 1, 1, 1), tip_lateral, 1e-2 * tip_lateral);
  EXPECT_NEAR(entry(c, 1, 2, 1, 2), tip_lateral, 1e-2 * tip_lateral);  // the other lateral axis
  EXPECT_NEAR(entry(c, 0, 1, 1, 1), mid_under_tip_load, 1e-2 * mid_under_tip_load);
  EXPECT_NEAR(entry(c, 0, 1, 0, 1), mid_lateral, 1e-2 * mid_lateral);
  EXPECT_NEAR(entry(c, 1, 0, 1, 0), l / ea, 1e-2 * l / ea);
  EXPECT_NEAR(entry(c, 0, 0, 1, 0), x / ea, 1e-2 * x / ea);  // axial: the mid node moves what lies before it
  // W is filled symmetric (contact_compliance solves for each node's motion and that of the
  // nodes after it, Maxwell-Betti gives the rest): the mid-under-tip entry above is the tip's
  // motion under a push on the mid node, checked against the beam. And positive definite
  EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(probe.w_).info(), Eigen::Success);
  // a lateral push moves neither node axially (the straight beam, to first order)
  EXPECT_LT(std::abs(entry(c, 1, 0, 1, 1)), 1e-9 * tip_lateral);
}

// the mid node's static compliance at 20 and 40 segments: its error against the beam falls by
// about four (second order), so what is left is the discretisation, not the operator
TEST(RodContactCompliance, ItsStaticErrorFallsAsTheSquareOfTheSegmentLength) {
  double error[2] = {0.0, 0.0};
  for (int k = 0; k < 2; ++k) {
    CosseratRodParams p = straight_rod();
    p.segments = 20 << k;
    CosseratRod rod = make_unit_cantilever(p);
    ComplianceProbe probe({p.segments / 2});
    const double h = 100.0;
    rod.step(h, &probe);
    ASSERT_TRUE(probe.ok_);
    const double x = 0.5 * p.length_m, beam = x * x * x / (3.0 * p.bending_stiffness_nm2);
    error[k] = std::abs(h * h * entry(probe.w_, 0, 1, 0, 1) - beam) / beam;
  }
  std::printf("mid-node static compliance error: %.3g %% at 20 segments, %.3g %% at 40\n", 100 * error[0],
              100 * error[1]);
  EXPECT_GT(error[0] / error[1], 3.5);
  EXPECT_LT(error[1], 2e-3);
}

TEST(RodContactCompliance, OverAVeryShortSubstepIsTheInverseNodeMass) {
  const CosseratRodParams p = straight_rod();
  CosseratRod rod = make_unit_cantilever(p);
  ComplianceProbe probe({3, kSegments});
  rod.step(1e-7, &probe);
  ASSERT_TRUE(probe.ok_);
  const double m_inner = rod.node_mass_kg(3), m_tip = rod.node_mass_kg(kSegments);
  EXPECT_NEAR(entry(probe.w_, 0, 1, 0, 1), 1.0 / m_inner, 1e-3 / m_inner);
  EXPECT_NEAR(entry(probe.w_, 1, 2, 1, 2), 1.0 / m_tip, 1e-3 / m_tip);
  // axially too: in 0.1 us the push travels 0.3 mm (sqrt(EA / mu) = 3.2 km/s), not a segment
  EXPECT_NEAR(entry(probe.w_, 1, 0, 1, 0), 1.0 / m_tip, 1e-3 / m_tip);
  EXPECT_LT(std::abs(entry(probe.w_, 0, 1, 1, 1)), 1e-6 / m_tip);  // and reaches no other node
}

TEST(RodContactCompliance, ImpulsesMoveTheNodesByWTimesThemAndLoadTheClampWithTheirForce) {
  const CosseratRodParams p = straight_rod();
  CosseratRod rod = make_unit_cantilever(p);
  ComplianceProbe probe({7, 12, kSegments});
  const double h = 100.0;
  const std::array<Eigen::Vector3d, 3> force_n = {Eigen::Vector3d(0.0, 0.2, 0.0), Eigen::Vector3d(0.1, 0.0, -0.1),
                                                  Eigen::Vector3d(-0.3, -0.05, 0.02)};
  for (const Eigen::Vector3d& f : force_n) probe.impulses_.push_back(f * h * h);
  rod.step(h, &probe);
  ASSERT_TRUE(probe.ok_ && probe.applied_);
  Eigen::VectorXd impulse(9), moved(9);
  for (int a = 0; a < 3; ++a) {
    impulse.segment<3>(3 * a) = probe.impulses_[a];
    const int node = probe.nodes_[a];
    moved.segment<3>(3 * a) = rod.nodes_m()[node] - probe.before_[node];
  }
  const Eigen::VectorXd predicted = probe.w_ * impulse;
  EXPECT_LT((moved - predicted).norm(), 1e-7 * predicted.norm());
  // statics: the clamp takes the applied forces (the moment too, through the frame)
  const Eigen::Vector3d total = force_n[0] + force_n[1] + force_n[2];
  EXPECT_LT((rod.hub_force_n() - total).norm(), 1e-5 * total.norm()) << rod.hub_force_n().transpose();
}

TEST(RodContactCompliance, RefusesNodesThatAreNotFreeOrNotIncreasing) {
  CosseratRod rod = make_unit_cantilever(straight_rod());
  ComplianceProbe clamp({0}), repeated({4, 4}), past_tip({kSegments + 1});
  rod.step(0.01, &clamp);
  EXPECT_FALSE(clamp.ok_);
  rod.step(0.01, &repeated);
  EXPECT_FALSE(repeated.ok_);
  rod.step(0.01, &past_tip);
  EXPECT_FALSE(past_tip.ok_);
}

}  // namespace
}  // namespace pcisim::physics::rod
