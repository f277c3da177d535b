#include "haptics/force_evaluator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace pcisim::haptics {
namespace {

constexpr int64_t kTickUs = 1000;

physics::LocalForceModel model_at(int64_t now_us, double f0_n, double k = 0.0) {
  physics::LocalForceModel m;
  m.made_utime = now_us;
  m.valid_for_us = 66'667;  // two 30 Hz periods
  m.f0_n = f0_n;
  m.k_n_per_m = k;
  return m;
}

InstrumentSample fresh_sample(int64_t now_us, double insertion_m = 0.0) {
  InstrumentSample s;
  s.received_us = now_us;
  s.insertion_m = insertion_m;
  return s;
}

// ticks at 1 kHz from t0 for n ticks, re-stamping the instrument each tick
ForceOutput run(ForceEvaluator& e, int64_t& t_us, int n, double insertion_m = 0.0) {
  ForceOutput out;
  for (int i = 0; i < n; ++i) {
    t_us += kTickUs;
    out = e.tick(fresh_sample(t_us, insertion_m), t_us);
  }
  return out;
}

HapticParams fast_params() {
  HapticParams p;
  p.ramp_in_ms = 10;
  p.slew_n_per_s = 1000;
  return p;
}

TEST(ForceEvaluator, EvaluatesTheLocalModelAfterRampIn) {
  ForceEvaluator e(fast_params());
  int64_t t = 1'000'000;
  e.set_model(model_at(t, 1.0, 100.0), t);
  // keep the model fresh while ramping in
  ForceOutput out;
  for (int i = 0; i < 40; ++i) {
    e.set_model(model_at(t, 1.0, 100.0), t);
    out = run(e, t, 1, 0.002);
  }
  EXPECT_NEAR(out.axial_force_n, 1.0 + 100.0 * 0.002, 1e-9);  // f0 + K (x - x0)
  EXPECT_EQ(out.flags & kFlagRamping, 0);
}

// the command carries the model's stiffness for a device's spring: K and Kt times the ramp's
// gain, none while fading, none on a clamped axis, none without a local model
TEST(ForceEvaluator, PublishesTheLocalStiffnessOnlyWhileItRendersTheLocalModel) {
  HapticParams p;
  p.ramp_in_ms = 100;
  p.slew_n_per_s = 1e5;
  p.fade_ms = 20;
  ForceEvaluator e(p);
  int64_t t = 1'000'000;
  physics::LocalForceModel m = model_at(t, 1.0, 200.0);
  m.kt_nm_per_rad = 0.004;
  e.set_model(m, t);
  ForceOutput out = run(e, t, 10);
  EXPECT_NEAR(out.axial_stiffness_n_per_m, 200.0 * 0.1, 1e-9) << "a tenth of the way through the ramp";
  EXPECT_NEAR(out.torsional_stiffness_nm_per_rad, 0.004 * 0.1, 1e-12);
  for (int i = 0; i < 100; ++i) {
    m.made_utime = t;
    e.set_model(m, t);
    out = run(e, t, 1);
  }
  EXPECT_DOUBLE_EQ(out.axial_stiffness_n_per_m, 200.0);
  EXPECT_DOUBLE_EQ(out.torsional_stiffness_nm_per_rad, 0.004);
  // the instrument falls silent: the force fades, the spring is gone at once
  for (int i = 0; i < 60; ++i) {
    t += kTickUs;
    out = e.tick(InstrumentSample{}, t);
  }
  EXPECT_TRUE(out.flags & kFlagFaded);
  EXPECT_EQ(out.axial_stiffness_n_per_m, 0.0);
  EXPECT_EQ(out.torsional_stiffness_nm_per_rad, 0.0);
  // a clamped axis has none; the other keeps its own
  p.ramp_in_ms = 1;
  p.peak_force_n = 0.5;
  ForceEvaluator clamped(p);
  for (int i = 0; i < 20; ++i) {
    m.made_utime = t;
    clamped.set_model(m, t);
    out = run(clamped, t, 1);
  }
  EXPECT_TRUE(out.flags & kFlagClamped);
  EXPECT_EQ(out.axial_stiffness_n_per_m, 0.0);
  EXPECT_DOUBLE_EQ(out.torsional_stiffness_nm_per_rad, 0.004);
  // a zero-order hold has no local model to give
  p.interpolation = Interpolation::kZeroOrderHold;
  p.peak_force_n = 4.0;
  ForceEvaluator hold(p);
  for (int i = 0; i < 20; ++i) {
    m.made_utime = t;
    hold.set_model(m, t);
    out = run(hold, t, 1);
  }
  EXPECT_DOUBLE_EQ(out.axial_force_n, 1.0);
  EXPECT_EQ(out.axial_stiffness_n_per_m, 0.0);
}

TEST(ForceEvaluator, RampsInOnStartInsteadOfJumping) {
  HapticParams p;
  p.ramp_in_ms = 100;
  p.slew_n_per_s = 1e5;
  ForceEvaluator e(p);
  int64_t t = 1'000'000;
  e.set_model(model_at(t, 2.0), t);
  const ForceOutput first = run(e, t, 1);
  EXPECT_NEAR(first.axial_force_n, 2.0 * 0.01, 1e-9) << "one tick of a 100 ms ramp";
  EXPECT_TRUE(first.flags & kFlagRamping);
  const ForceOutput half = run(e, t, 49);
  EXPECT_NEAR(half.axial_force_n, 1.0, 1e-9);
}

TEST(ForceEvaluator, ClampsToThePeakForce) {
  HapticParams p = fast_params();
  p.peak_force_n = 3.0;
  p.slew_n_per_s = 1e6;
  ForceEvaluator e(p);
  int64_t t = 1'000'000;
  ForceOutput out;
  for (int i = 0; i < 50; ++i) {
    e.set_model(model_at(t, 50.0), t);
    out = run(e, t, 1);
  }
  EXPECT_DOUBLE_EQ(out.axial_force_n, 3.0);
  EXPECT_TRUE(out.flags & kFlagClamped);
}

TEST(ForceEvaluator, SlewLimitsAStepInTheModel) {
  HapticParams p = fast_params();
  p.slew_n_per_s = 100;  // 0.1 N per tick
  p.blend_ms = 0;        // no blending: only the slew limit stands between
  ForceEvaluator e(p);
  int64_t t = 1'000'000;
  for (int i = 0; i < 50; ++i) {
    e.set_model(model_at(t, 0.0), t);
    run(e, t, 1);
  }
  double last = 0.0;
  for (int i = 0; i < 30; ++i) {
    e.set_model(model_at(t, 2.0), t);
    const ForceOutput out = run(e, t, 1);
    EXPECT_LE(std::abs(out.axial_force_n - last), 0.1 + 1e-12);
    last = out.axial_force_n;
  }
  EXPECT_NEAR(last, 2.0, 1e-9);
}

TEST(ForceEvaluator, BlendingMakesNoStepLargerThanTheSlewLimit) {
  HapticParams p = fast_params();
  p.slew_n_per_s = 1e6;  // slew effectively off: blending alone must smooth the change
  p.blend_ms = 10;
  ForceEvaluator e(p);
  int64_t t = 1'000'000;
  for (int i = 0; i < 50; ++i) {
    e.set_model(model_at(t, 0.0), t);
    run(e, t, 1);
  }
  e.set_model(model_at(t, 1.0), t);
  double last = 0.0, biggest = 0.0;
  for (int i = 0; i < 20; ++i) {
    const double f = run(e, t, 1).axial_force_n;
    biggest = std::max(biggest, std::abs(f - last));
    last = f;
  }
  EXPECT_NEAR(last, 1.0, 1e-9);
  EXPECT_LE(biggest, 0.1 + 1e-9) << "a 1 N model change spread over 10 ms";
}

TEST(ForceEvaluator, StaleModelFadesToZeroAndRecovers) {
  HapticParams p = fast_params();
  p.fade_ms = 50;
  ForceEvaluator e(p);
  int64_t t = 1'000'000;
  for (int i = 0; i < 50; ++i) {
    e.set_model(model_at(t, 1.0), t);
    run(e, t, 1);
  }
  // physics stalls: the model is older than its validity after ~67 ms, then fades over 50 ms
  ForceOutput out = run(e, t, 65);  // the model was made a tick before the loop ended
  EXPECT_NEAR(out.axial_force_n, 1.0, 1e-9);
  out = run(e, t, 25);
  EXPECT_TRUE(out.flags & kFlagStale);
  EXPECT_TRUE(out.flags & kFlagFaded);
  EXPECT_GT(out.axial_force_n, 0.0);
  EXPECT_LT(out.axial_force_n, 0.8);
  out = run(e, t, 30);
  EXPECT_DOUBLE_EQ(out.axial_force_n, 0.0);
  // physics resumes
  for (int i = 0; i < 60; ++i) {
    e.set_model(model_at(t, 1.0), t);
    out = run(e, t, 1);
  }
  EXPECT_NEAR(out.axial_force_n, 1.0, 1e-9);
}

TEST(ForceEvaluator, SilentInstrumentFadesToZero) {
  HapticParams p = fast_params();
  p.instrument_timeout_ms = 50;
  p.fade_ms = 20;
  ForceEvaluator e(p);
  int64_t t = 1'000'000;
  for (int i = 0; i < 50; ++i) {
    e.set_model(model_at(t, 1.0), t);
    run(e, t, 1);
  }
  InstrumentSample last = fresh_sample(t);
  ForceOutput out;
  for (int i = 0; i < 49; ++i) {
    t += kTickUs;
    e.set_model(model_at(t, 1.0), t);
    out = e.tick(last, t);
  }
  EXPECT_NEAR(out.axial_force_n, 1.0, 1e-9) << "49 ms of silence is still fine";
  for (int i = 0; i < 25; ++i) {
    t += kTickUs;
    e.set_model(model_at(t, 1.0), t);
    out = e.tick(last, t);
  }
  EXPECT_TRUE(out.flags & kFlagFaded);
  EXPECT_DOUBLE_EQ(out.axial_force_n, 0.0);
}

TEST(ForceEvaluator, NonFiniteModelGivesZeroForceACountedFaultAndARampIn) {
  ForceEvaluator e(fast_params());
  int64_t t = 1'000'000;
  for (int i = 0; i < 50; ++i) {
    e.set_model(model_at(t, 1.0), t);
    run(e, t, 1);
  }
  e.set_model(model_at(t, std::numeric_limits<double>::quiet_NaN()), t);
  ForceOutput out = run(e, t, 1);
  EXPECT_EQ(out.axial_force_n, 0.0);
  EXPECT_TRUE(out.flags & kFlagFault);
  EXPECT_EQ(e.faults(), 1);
  e.set_model(model_at(t, 1.0), t);
  out = run(e, t, 1);
  EXPECT_TRUE(out.flags & kFlagRamping) << "after a fault force comes back gradually";
  EXPECT_LT(out.axial_force_n, 0.5);
  EXPECT_TRUE(std::isfinite(out.axial_force_n));
}

TEST(ForceEvaluator, ZeroOrderHoldHoldsAndExtrapolationExtendsThePhysicsForce) {
  HapticParams p = fast_params();
  p.passivity = false;
  p.slew_n_per_s = 1e6;
  HapticParams zoh = p, lin = p;
  zoh.interpolation = Interpolation::kZeroOrderHold;
  lin.interpolation = Interpolation::kLinearExtrapolation;
  ForceEvaluator e_zoh(zoh), e_lin(lin);
  int64_t t = 1'000'000;
  // physics forces 1 N then 2 N, 33 ms apart, rising at 30 N/s
  for (ForceEvaluator* e : {&e_zoh, &e_lin}) {
    int64_t ti = t;
    for (int i = 0; i < 50; ++i) {
      e->set_model(model_at(ti, 1.0, 500.0), ti);
      run(*e, ti, 1);
    }
  }
  t += 50 * kTickUs;
  auto m1 = model_at(t - 33'000, 1.0, 500.0), m2 = model_at(t, 2.0, 500.0);
  for (ForceEvaluator* e : {&e_zoh, &e_lin}) {
    e->set_model(m1, t);
    e->set_model(m2, t);
  }
  int64_t t_zoh = t, t_lin = t;
  const double f_zoh = run(e_zoh, t_zoh, 10, 0.05).axial_force_n;
  const double f_lin = run(e_lin, t_lin, 10, 0.05).axial_force_n;
  EXPECT_NEAR(f_zoh, 2.0, 1e-9) << "held, K ignored";
  EXPECT_NEAR(f_lin, 2.0 + 10.0 / 33.0, 1e-9) << "10 ms along the 30 N/s trend";
}

TEST(ForceEvaluator, PassivityAddsDampingWhenTheModelWouldPushTheTrainee) {
  HapticParams p = fast_params();
  p.slew_n_per_s = 1e6;
  ForceEvaluator e(p);
  int64_t t = 1'000'000;
  physics::LocalForceModel active = model_at(t, 0.0);
  active.b_n_s_per_m = -20.0;  // negative damping pushes along the motion: generates energy
  ForceOutput out;
  bool damped = false;
  for (int i = 0; i < 300; ++i) {
    active.made_utime = t;
    e.set_model(active, t);
    t += kTickUs;
    InstrumentSample s = fresh_sample(t, 0.0);
    s.insertion_rate_m_per_s = 0.01;
    out = e.tick(s, t);
    damped |= (out.flags & kFlagDamped) != 0;
    EXPECT_GE(e.axial_passivity().energy(), -1e-9) << "tick " << i;
  }
  EXPECT_TRUE(damped);
}

TEST(ForceEvaluator, NoModelMeansNoForce) {
  ForceEvaluator e(fast_params());
  int64_t t = 1'000'000;
  const ForceOutput out = run(e, t, 100);
  EXPECT_EQ(out.axial_force_n, 0.0);
  EXPECT_TRUE(out.flags & kFlagStale);
}

TEST(ForceEvaluator, NonFiniteOrNegativeLimitsAreRefusedByName) {
  // a NaN peak would pass a NaN force to the motors; a negative slew is an inverted clamp
  const std::pair<const char*, void (*)(HapticParams&)> cases[] = {
      {"haptics.peak_force_n", [](HapticParams& p) { p.peak_force_n = std::nan(""); }},
      {"haptics.slew_n_per_s", [](HapticParams& p) { p.slew_n_per_s = -1.0; }},
      {"haptics.instrument_timeout_ms", [](HapticParams& p) { p.instrument_timeout_ms = std::nan(""); }},
      {"haptics.passivity_max_damping_n_s_per_m",
       [](HapticParams& p) { p.passivity_max_damping_n_s_per_m = INFINITY; }},
  };
  for (const auto& [field, spoil] : cases) {
    HapticParams p;
    spoil(p);
    try {
      ForceEvaluator e(p);
      ADD_FAILURE() << field << " accepted";
    } catch (const std::invalid_argument& err) {
      EXPECT_EQ(std::string(err.what()).rfind(field, 0), 0u) << err.what();
    }
  }
  EXPECT_NO_THROW(ForceEvaluator{HapticParams{}});
}

}  // namespace
}  // namespace pcisim::haptics
