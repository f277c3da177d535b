#include "haptics/passivity_controller.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pcisim::haptics {
namespace {

TEST(PassivityController, LeavesAPassiveForceAlone) {
  PassivityController pc;
  // a spring the trainee pushes in and lets out: energy goes up and back to zero, never below
  double x = 0;
  for (int i = 0; i < 2000; ++i) {
    const double v = 0.01 * std::sin(i * 1e-3 * 2 * M_PI);
    x += v * 1e-3;
    const double f = 100.0 * x;
    EXPECT_DOUBLE_EQ(pc.filter(f, v, 1e-3), f);
  }
  EXPECT_GE(pc.energy(), 0.0);
  EXPECT_LT(pc.energy(), 1e-5) << "what the spring still stores after one cycle";
}

TEST(PassivityController, DampsAnActiveEnvironmentBackToZeroEnergy) {
  PassivityController on, off(0.0);  // max damping 0: observer only
  // a negative damper pushes along the motion: it generates energy
  double e_off_min = 0;
  for (int i = 0; i < 1000; ++i) {
    const double v = 0.02;
    const double f_active = -5.0 * v;
    const double f_on = on.filter(f_active, v, 1e-3);
    off.filter(f_active, v, 1e-3);
    EXPECT_GE(on.energy(), -1e-12) << "tick " << i;
    EXPECT_GE(f_on, -1e-12) << "the controller cancels the pushing force";
    e_off_min = std::min(e_off_min, off.energy());
  }
  EXPECT_LT(e_off_min, -1e-3) << "without the controller the energy runs away";
}

}  // namespace
TEST(PassivityController, BooksTheEnergyOfTheDisplayedForceNotTheClampedAway) {
  // 10 N asked, 4 N the most the device shows: the trainee's 1 m/s over 1 ms put in 4 mJ, not 10
  PassivityController pc;
  EXPECT_DOUBLE_EQ(pc.filter(10.0, 1.0, 1e-3, 4.0), 10.0) << "the clamp itself is the caller's";
  EXPECT_DOUBLE_EQ(pc.energy(), 4e-3);
  // then a 10 N push along the motion: 6 mJ too much; damping 6 N s/m brings it to -4 N
  EXPECT_DOUBLE_EQ(pc.filter(-10.0, 1.0, 1e-3, 4.0), -4.0);
  EXPECT_DOUBLE_EQ(pc.last_damping(), 6.0);
  EXPECT_NEAR(pc.energy(), 0.0, 1e-15) << "damped back to passive";
}

}  // namespace pcisim::haptics
