// The trainee's force (eqs 19-20) as the local force model the haptic loop evaluates: friction
// resists the way the wire moves, the model lives two physics periods, and turning against
// the wall gives a torque that resists the turn.
#include "physics/guidewire/wire_feedback.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/physics/guidewire/wire_test_support.h"
#include "tests/common/shared_lumen.h"

namespace pcisim::physics {
namespace {

TEST(WireFeedback, FrictionResistsPushAndPullAndTheModelLivesTwoPeriods) {
  World world = test::make_world(test::default_scene());
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
  World world = test::make_world(test::default_scene());
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

namespace pcisim::physics {
namespace {

TEST(WireFeedback, EqTwentyAsWrittenFollowsTheFirstLinksChangeAndIsZeroAtRest) {
  // the chain-mail down the LCx, pushed 100 mm further over 10 s (the hard case), then held 2 s.
  // Both F_internal variants from the same state every step: eq 20 (k times the first free link's
  // change of length since the last step) moves while the wire is pushed and is zero once it
  // rests, whatever load it still carries; the figures are docs/guidewire.md's
  World world = test::make_world(test::default_scene());
  test::BranchScript script;
  script.turn_deg = -90.0;
  const double dt = test::default_scene().step_s;
  auto feedback = [&world] {
    return compute_feedback(*world.guidewire_state(), *test::default_scene().guidewire, world.contact_state(),
                            world.friction_state());
  };
  double rms = 0.0, eq20_max = 0.0, refused_max = 0.0;
  int n = 0;
  for (double t = 0.0; t <= script.end_s(); t += dt) {
    world.step(script.at(t));
    const WireFeedback f = feedback();
    rms += std::pow(f.internal_eq20_n - f.internal_refused_feed_n, 2);
    ++n;
  }
  InstrumentInput in = script.at(script.end_s());
  const double start_m = in.insertion_m;
  for (double s = 0.0; s <= 10.0; s += dt) {
    in.insertion_m = start_m + 0.1 * std::min(s / 10.0, 1.0);
    world.step(in);
    const WireFeedback f = feedback();
    ASSERT_TRUE(std::isfinite(f.internal_eq20_n));
    rms += std::pow(f.internal_eq20_n - f.internal_refused_feed_n, 2);
    ++n;
    eq20_max = std::max(eq20_max, std::abs(f.internal_eq20_n));
    refused_max = std::max(refused_max, f.internal_refused_feed_n);
  }
  for (double s = 0.0; s <= 2.0; s += dt) world.step(in);
  const WireFeedback rest = feedback();
  std::printf(
      "F_internal over the script and the 100 mm push: rms(eq 20 - refused feed) %.4f N; |eq 20| up to %.4f N, refused "
      "feed up to %.4f N; at rest eq 20 %.2e N\n",
      std::sqrt(rms / n), eq20_max, refused_max, rest.internal_eq20_n);
  EXPECT_GT(eq20_max, 1e-3);
  EXPECT_LT(std::abs(rest.internal_eq20_n), 1e-6);
}

}  // namespace
}  // namespace pcisim::physics
