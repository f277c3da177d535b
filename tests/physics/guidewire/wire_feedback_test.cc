// The trainee's force (eqs 19-20) as the local force model the haptic loop evaluates: friction
// resists the way the wire moves, the model lives two physics periods, and turning against
// the wall gives a torque that resists the turn.
#include "physics/guidewire/wire_feedback.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/physics/guidewire/wire_test_support.h"

namespace pcisim::physics {
namespace {

TEST(WireFeedback, FrictionResistsPushAndPullAndTheModelLivesTwoPeriods) {
  World world(test::default_scene());
  test::BranchScript script;
  const double dt = test::default_scene().step_s;
  double push_sum = 0.0, pull_sum = 0.0;
  int push_n = 0, pull_n = 0;
  for (double t = 0.0; t <= script.end_s(); t += dt) {
    InstrumentInput in = script.at(t);
    const double rate = (script.at(t + dt).insertion_m - script.at(t - dt).insertion_m) / (2.0 * dt);
    in.insertion_rate_m_per_s = rate;
    world.step(in);
    const LocalForceModel m = world.force_model();
    ASSERT_EQ(m.valid_for_us, static_cast<int64_t>(std::llround(2e6 * dt)));
    ASSERT_NEAR(m.made_utime * 1e-6, world.time_s(), 1e-6);
    ASSERT_DOUBLE_EQ(m.x0_m, in.insertion_m);
    ASSERT_GE(m.k_n_per_m, 0.0);
    ASSERT_GE(m.b_n_s_per_m, 0.0);
    ASSERT_GE(m.kt_nm_per_rad, 0.0);
    if (t > 10.0 && t < 16.5) {  // advancing down the LAD, wire against the walls
      push_sum += m.f0_n;
      ++push_n;
    }
    if (t > 17.6 && t < 18.4) {  // pulling back
      pull_sum += m.f0_n;
      ++pull_n;
    }
  }
  ASSERT_GT(push_n, 0);
  ASSERT_GT(pull_n, 0);
  EXPECT_GT(push_sum / push_n, 0.0);  // positive resists insertion
  EXPECT_LT(pull_sum / pull_n, 0.0);  // and a pull is resisted the other way
}

TEST(WireFeedback, TorqueResistsTheTurnWhileTheTipTouches) {
  World world(test::default_scene());
  test::BranchScript script;
  const double dt = test::default_scene().step_s;
  for (double t = 0.0; t <= script.end_s(); t += dt) world.step(script.at(t));
  InstrumentInput in = script.at(script.end_s());
  for (const double rate : {2.0, -2.0}) {
    double sum = 0.0;
    for (int k = 0; k < 15; ++k) {
      in.rotation_rad += rate * dt;
      in.rotation_rate_rad_per_s = rate;
      world.step(in);
      sum += world.force_model().t0_nm;
    }
    EXPECT_GT(sum * rate, 0.0) << "rate " << rate;  // same sign as the turn: it resists it
  }
  in.rotation_rate_rad_per_s = 0.0;
  world.step(in);
  EXPECT_EQ(world.force_model().t0_nm, 0.0);  // a hand at rest is not turned by friction
}

TEST(WireFeedback, NonFiniteFeedbackInvalidatesTheModel) {
  WireFeedback f;
  f.friction_n = std::nan("");
  const LocalForceModel m = to_local_force_model(f, InstrumentInput{}, GuidewireParams{}, 1.0, 1.0 / 30.0);
  EXPECT_EQ(m.valid_for_us, 0);  // the haptic loop fades to zero on an invalid model
}

}  // namespace
}  // namespace pcisim::physics
