// Coulomb friction (eqs 16-18): static friction holds a node whose tangential motion is within
// mu_s |dp_n|, kinetic friction shortens it by mu_k |dp_n|; friction never pushes a node
// forward, never reverses its motion and stays inside the Coulomb cone.
#include "physics/guidewire/coulomb_friction.h"

#include <gtest/gtest.h>

#include <cmath>

#include "physics/guidewire/wall_contact.h"
#include "tests/physics/guidewire/wire_test_support.h"
#include "tests/common/shared_lumen.h"

namespace pcisim::physics {
namespace {

class PlaneLumen final : public LumenQuery {
 public:
  WallSample sample(const Eigen::Vector3d& p) const override {
    WallSample s;
    s.distance_m = p.z() - 0.5e-3;  // lumen below z = 0.5 mm
    s.normal = Eigen::Vector3d::UnitZ();
    return s;
  }
};

struct Bench {
  GuidewireParams gp;
  VesselContactParams cp;
  FrictionParams fp;
  PlaneLumen lumen;
  ChainMailWire wire;
  WallContact contact;
  CoulombFriction friction;
  static GuidewireParams params() {
    GuidewireParams p;
    p.length_m = 0.02;
    p.segment_count = 20;
    p.tip_length_m = 0.005;
    p.tip_angle_deg = 0.0;
    return p;
  }
  Bench()
      : gp(params()),
        wire(gp, CatheterPath({Eigen::Vector3d(-0.05, 0.0, 0.0), Eigen::Vector3d::Zero()})),
        contact(cp, lumen, wire.node_count()),
        friction(fp, wire.node_count()) {
    wire.begin_step(0.015, 0.0);
    wire.restore_limits();
    wire.end_step();
    wire.begin_step(0.015, 0.0);  // a step without feed: motion is measured from here
    contact.begin_step();
    friction.begin_step(wire);
  }
  // presses node k into the wall by `into_m` and slides it by `slide_m` along x, then runs one
  // contact pass and one friction pass; returns the node's final position
  Eigen::Vector3d press(int k, double into_m, double slide_m) {
    auto x = wire.mutable_nodes_m();
    x[k].z() = 0.5e-3 + into_m;
    x[k].x() += slide_m;
    contact.project(wire);
    friction.apply(wire, contact);
    return wire.nodes_m()[k];
  }
};

TEST(CoulombFriction, StaticFrictionHoldsASmallSlide) {
  Bench b;
  const int k = 10;  // a body node
  const Eigen::Vector3d start = b.wire.step_start_nodes_m()[k];
  // |dp_n| = 0.3 mm + eps, mu_s 0.10: a 0.02 mm slide is held
  const Eigen::Vector3d p = b.press(k, 0.3e-3, 0.02e-3);
  EXPECT_NEAR(p.x(), start.x(), 1e-12);
  EXPECT_EQ(b.friction.stuck()[k], 1);
}

TEST(CoulombFriction, KineticFrictionShortensALargeSlideByMuKTimesTheNormalCorrection) {
  Bench b;
  const int k = 10;
  const Eigen::Vector3d start = b.wire.step_start_nodes_m()[k];
  const double slide = 0.5e-3;
  const Eigen::Vector3d p = b.press(k, 0.3e-3, slide);
  const double dn = 0.3e-3 + b.cp.wall_margin_m;
  EXPECT_NEAR(p.x() - start.x(), slide - b.fp.body_kinetic * dn, 1e-12);
  EXPECT_EQ(b.friction.stuck()[k], 0);
}

TEST(CoulombFriction, TipUsesItsOwnCoefficients) {
  Bench b;
  const int k = b.wire.node_count() - 1;
  ASSERT_TRUE(b.wire.node_in_tip(k));
  const Eigen::Vector3d start = b.wire.step_start_nodes_m()[k];
  const double slide = 0.5e-3;
  const Eigen::Vector3d p = b.press(k, 0.3e-3, slide);
  const double dn = 0.3e-3 + b.cp.wall_margin_m;
  EXPECT_NEAR(p.x() - start.x(), slide - b.fp.tip_kinetic * dn, 1e-12);
}

TEST(CoulombFriction, NeverPushesForwardAndStaysInsideTheCoulombConeInTheCoronaryTree) {
  // every friction pass of the scripted sessions (LAD and LCx): the correction opposes the
  // tangential motion, is never longer than it, and is either a full stop within the static
  // cone or at most mu_k |dp_n| long
  int checked = 0;
  for (double turn : {90.0, -90.0}) {
    World world = test::make_world(test::default_scene());
    test::BranchScript script;
    script.turn_deg = turn;
    const FrictionParams fp = world.friction_state()->params();
    for (double t = 0.0; t <= script.end_s(); t += test::default_scene().step_s) {
      world.step(script.at(t));
      const CoulombFriction& f = *world.friction_state();
      const ChainMailWire& w = *world.guidewire_state();
      for (int i = w.first_free_node(); i < w.node_count(); ++i) {
        const Eigen::Vector3d dt = f.pass_tangential_m()[i];
        const Eigen::Vector3d c = f.pass_correction_m()[i];
        const double limit_s = f.pass_static_limit_m()[i];
        if (limit_s <= 0.0) continue;  // not touching in the last pass
        ++checked;
        const double mu_s = w.node_in_tip(i) ? fp.tip_static : fp.body_static;
        const double mu_k = w.node_in_tip(i) ? fp.tip_kinetic : fp.body_kinetic;
        const double dn = limit_s / mu_s;
        ASSERT_LE(c.dot(dt), 1e-18) << "friction pushed node " << i << " forward at t " << t;
        ASSERT_LE(c.norm(), dt.norm() + 1e-15) << "friction reversed node " << i;
        if (f.stuck()[i]) {
          ASSERT_LE(dt.norm(), limit_s + 1e-15);
          ASSERT_LE((c + dt).norm(), 1e-15);
        } else {
          ASSERT_LE(c.norm(), mu_k * dn + 1e-15) << "outside the kinetic cone at node " << i;
        }
      }
    }
  }
  EXPECT_GT(checked, 1000);
}

}  // namespace
}  // namespace pcisim::physics
