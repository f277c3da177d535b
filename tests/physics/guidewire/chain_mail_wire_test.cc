// Chain-mail guidewire: the limits of eqs 1-4 hold after every step, push/pull move the tip,
// and turning the proximal end turns the tip's bend plane.
#include "physics/guidewire/chain_mail_wire.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "anatomy/phantom/coronary_phantom.h"
#include "tests/physics/guidewire/wire_test_support.h"
#include "tests/common/shared_lumen.h"

namespace pcisim::physics {
namespace {

using test::BranchScript;
using test::check_limits;
using test::kDeg;

ChainMailWire free_wire(const GuidewireParams& p = GuidewireParams{}) {
  return ChainMailWire(p, CatheterPath(anatomy::guide_catheter_path(anatomy::make_coronary_phantom({1}))));
}

void step_free(ChainMailWire& w, double insertion_m, double rotation_rad, int passes = 2) {
  w.begin_step(insertion_m, rotation_rad);
  for (int k = 0; k < passes; ++k) w.optimise_pass(k);
  w.restore_limits();
  w.end_step();
}

// the tip's sideways direction: where the tip node sits off the line of the last body link
Eigen::Vector3d tip_lateral(const ChainMailWire& w) {
  const auto x = w.nodes_m();
  int last_body = w.segment_count() - 1;
  while (last_body > 0 && w.links()[last_body].tip) --last_body;
  const Eigen::Vector3d t = (x[last_body + 1] - x[last_body]).normalized();
  Eigen::Vector3d lat = x.back() - x[last_body + 1];
  lat -= lat.dot(t) * t;
  return lat;
}

TEST(ChainMailWire, LimitsHoldAfterEveryStepOfAFreeWire) {
  ChainMailWire w = free_wire();
  for (int k = 0; k < 120; ++k) {
    step_free(w, 0.0005 * std::min(k, 60), 0.05 * k);
    const auto r = check_limits(w);
    ASSERT_EQ(r.bad_links, 0) << "step " << k << " length excess " << r.worst_length_ratio_excess << " shear excess "
                              << r.worst_shear_excess_rad;
  }
  EXPECT_LT(w.first_free_node(), w.node_count());
}

TEST(ChainMailWire, LimitsHoldAfterEveryStepInTheCoronaryTree) {
  // the whole default scene: contact, friction and blood flow all move nodes between sweeps
  for (double turn : {90.0, 270.0}) {
    World world = test::make_world(test::default_scene());
    BranchScript script;
    script.turn_deg = turn;
    const double dt = test::default_scene().step_s;
    int steps = 0;
    for (double t = 0.0; t <= script.end_s(); t += dt, ++steps) {
      world.step(script.at(t));
      const auto r = check_limits(*world.guidewire_state());
      ASSERT_EQ(r.bad_links, 0) << "turn " << turn << " t " << t << " length excess " << r.worst_length_ratio_excess
                                << " shear excess " << r.worst_shear_excess_rad;
    }
    EXPECT_GT(steps, 500);
  }
}

TEST(ChainMailWire, FreeWireKeepsItsRestShape) {
  // 20 mm out of the catheter in free space: rest lengths and the tip's pre-bend come back
  GuidewireParams p;
  ChainMailWire w = free_wire(p);
  for (int k = 0; k <= 40; ++k) step_free(w, 0.0005 * k, 0.0);
  for (int k = 0; k < 30; ++k) step_free(w, 0.020, 0.0);
  const auto x = w.nodes_m();
  const int n = w.segment_count();
  for (int j = w.first_free_node(); j < n; ++j) EXPECT_NEAR((x[j + 1] - x[j]).norm(), w.rest_length_m(), 1e-6);
  // total turn of the tip from its first to its last link: the pre-bend, tip_angle_deg
  int first_tip = n - 1;
  while (first_tip > 0 && w.links()[first_tip - 1].tip) --first_tip;
  const Eigen::Vector3d a = (x[first_tip] - x[first_tip - 1]).normalized();
  const Eigen::Vector3d b = (x[n] - x[n - 1]).normalized();
  EXPECT_NEAR(std::acos(std::clamp(a.dot(b), -1.0, 1.0)) / kDeg, p.tip_angle_deg, 3.0);
  // the body leaves the catheter straight
  const Eigen::Vector3d body = (x[first_tip - 1] - x[w.first_free_node()]).normalized();
  EXPECT_GT(body.dot(w.path().exit_direction()), std::cos(2.0 * kDeg));
}

TEST(ChainMailWire, RotatingTheProximalEndTurnsTheTip) {
  ChainMailWire w = free_wire();
  for (int k = 0; k <= 40; ++k) step_free(w, 0.0005 * k, 0.0);
  for (int k = 0; k < 30; ++k) step_free(w, 0.020, 0.0);  // let the tip settle
  const Eigen::Vector3d axis = w.path().exit_direction();
  const Eigen::Vector3d before = tip_lateral(w);
  ASSERT_GT(before.norm(), 2e-3);  // a 12 mm tip at 45 deg stands well off the body line
  // a quarter turn at the hand, ramped over a second
  for (int k = 1; k <= 30; ++k) step_free(w, 0.020, 90.0 * kDeg * k / 30.0);
  for (int k = 0; k < 30; ++k) step_free(w, 0.020, 90.0 * kDeg);
  const Eigen::Vector3d after = tip_lateral(w);
  const double angle = std::atan2(before.cross(after).dot(axis), before.dot(after)) / kDeg;
  EXPECT_NEAR(angle, 90.0, 5.0);  // same sense as the hand (right-handed about the wire)
  EXPECT_NEAR(after.norm(), before.norm(), 0.2e-3);
  // and the reported bend direction turns with it
  EXPECT_NEAR(w.tip_bend_direction().dot(after.normalized()), 1.0, 0.02);
  // a full turn back brings the tip back
  for (int k = 1; k <= 30; ++k) step_free(w, 0.020, 90.0 * kDeg * (1.0 - k / 30.0));
  for (int k = 0; k < 30; ++k) step_free(w, 0.020, 0.0);
  EXPECT_LT((tip_lateral(w) - before).norm(), 0.2e-3);
}

TEST(ChainMailWire, PushAdvancesAndPullRetractsTheTip) {
  ChainMailWire w = free_wire();
  for (int k = 0; k <= 40; ++k) step_free(w, 0.0005 * k, 0.0);
  const Eigen::Vector3d exit = w.path().exit_m();
  const double out20 = (w.nodes_m().back() - exit).norm();
  for (int k = 0; k <= 20; ++k) step_free(w, 0.020 + 0.0005 * k, 0.0);
  const double out30 = (w.nodes_m().back() - exit).norm();
  EXPECT_NEAR(out30 - out20, 0.010, 0.5e-3);
  EXPECT_NEAR(w.fed_length_m(), 0.030, 1e-12);
  for (int k = 0; k <= 20; ++k) step_free(w, 0.030 - 0.0005 * k, 0.0);
  EXPECT_NEAR((w.nodes_m().back() - exit).norm(), out20, 0.5e-3);
}

}  // namespace
}  // namespace pcisim::physics
