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

TEST(ForceEvaluator, NoModelMeansNoForce) {
  ForceEvaluator e(fast_params());
  int64_t t = 1'000'000;
  const ForceOutput out = run(e, t, 100);
  EXPECT_EQ(out.axial_force_n, 0.0);
  EXPECT_TRUE(out.flags & kFlagStale);
}

}  // namespace
}  // namespace pcisim::haptics
