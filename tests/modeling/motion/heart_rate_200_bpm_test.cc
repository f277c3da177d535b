// Hard case (issue #14, "Hard cases (tests): ... a 200 bpm sequence"): a synthetic cine of a heart
// beating at 200 bpm (a 0.3 s cycle) is turned into a motion file, and the beating heart runs that
// file at 200 bpm for 3 s at the physics thread's default step without going unstable. The cine
// renderer knows phases only: the rate enters as the truth's and the recovery's cycle (0.3 s), which
// the motion file carries, and as the heart's rate_bpm = 60 / cycle_s. Coarse and quick: 4 mm
// voxels, 6 frames, few demons iterations (accuracy: heart_motion_recovery_test.cc).
// Links physics beside modeling (tests/CMakeLists.txt: the modeling tests link pcisim_physics).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "anatomy/heart/synthetic_heart_motion.h"
#include "modeling/motion/demons_motion.h"
#include "modeling/motion/synthetic_cine.h"
#include "physics/heart/beating_heart.h"
#include "tests/physics/heart/heart_health.h"

namespace pcisim::modeling {
namespace {

namespace fs = std::filesystem;

constexpr double kCycleS = 60.0 / 200.0;
constexpr double kDt = 1.0 / 30;  // the physics thread's default step
constexpr double kBoundM = 0.030;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

TEST(HeartRate200Bpm, MotionRecoveredFromA200BpmCineDrivesTheHeartStably) {
  const auto t0 = std::chrono::steady_clock::now();
  anatomy::SyntheticMotionSpec truth_spec;
  truth_spec.cycle_s = kCycleS;
  const anatomy::HeartMotion truth = anatomy::make_synthetic_heart_motion(truth_spec);
  CineSpec spec;
  spec.frames = 6;  // 50 ms apart: a cine's temporal resolution at this rate
  spec.voxel_mm = Eigen::Vector3d::Constant(4.0);
  spec.supersample = 1;
  spec.noise_sigma = 0.02;
  const CineSequence cine = render_synthetic_cine(truth, spec);
  ASSERT_EQ(cine.cycle_s, kCycleS);

  DemonsOptions o;
  o.levels = 2;
  o.iterations = 20;
  const anatomy::HeartMotion recovered =
      recover_heart_motion(cine.frames, cine.cycle_s, anatomy::template_motion_grid(5e-3), {}, o);
  const double recovered_s = seconds_since(t0);
  EXPECT_EQ(recovered.frames(), 6);
  EXPECT_EQ(recovered.cycle_s(), kCycleS);

  // the file the scene names (heart_beat.motion_file), read back by the beating heart
  const fs::path path = fs::path(::testing::TempDir()) / ("pcisim-200bpm-" + std::to_string(::getpid()) + ".motion");
  recovered.write(path.string());
  EXPECT_EQ(anatomy::HeartMotion::read(path.string()).cycle_s(), kCycleS);
  physics::HeartBeatParams p;
  p.rate_bpm = 60.0 / recovered.cycle_s();
  EXPECT_NEAR(p.rate_bpm, 200.0, 1e-9);
  p.motion_file = path.string();
  physics::BeatingHeart h(p);
  fs::remove(path);

  // 3 s: 10 cycles, 9 steps of 1/30 s each (a step jumps 11 % of the cycle)
  const Eigen::Matrix3Xd& rest = h.rest_positions_m();
  physics::testing::HeartHealth worst;
  double driven_off_m = 0.0, driven_moved_m = 0.0;
  const int steps = static_cast<int>(std::lround(3.0 / kDt));
  for (int s = 0; s < steps; ++s) {
    h.step(kDt);
    const physics::testing::HeartHealth now = physics::testing::health(h);
    worst.merge(now);
    ASSERT_TRUE(now.finite) << "step " << s;
    // the driven particles sit where the recovered motion puts them at this phase
    for (int i : h.driven()) {
      const Eigen::Vector3d want = rest.col(i) + recovered.displacement_m(rest.col(i), h.phase());
      driven_off_m = std::max(driven_off_m, (h.positions_m().col(i) - want).norm());
      driven_moved_m = std::max(driven_moved_m, (want - rest.col(i)).norm());
    }
  }
  std::printf(
      "200 bpm: %zu cine frames of %lld x %lld x %lld voxels recovered in %.1f s; %d steps: max from rest %.2f mm "
      "(free %.2f mm), strain %.3f, driven off their recovered positions by %.2g mm (they move up to %.2f mm); "
      "%.1f s in all\n",
      cine.frames.size(), (long long)cine.frames[0].dims[0], (long long)cine.frames[0].dims[1],
      (long long)cine.frames[0].dims[2], recovered_s, steps, 1e3 * worst.max_from_rest_m,
      1e3 * worst.max_free_from_rest_m, worst.max_strain, 1e3 * driven_off_m, 1e3 * driven_moved_m, seconds_since(t0));
  EXPECT_NEAR(h.time_s(), 3.0, 1e-9);
  EXPECT_TRUE(worst.finite);
  EXPECT_LT(worst.max_from_rest_m, kBoundM);
  EXPECT_LT(worst.max_strain, 0.5);  // the built-in motion's 200 bpm hard case holds 0.5 too
  EXPECT_GT(driven_moved_m, 2e-3);   // the recovered motion moves the ventricles
  EXPECT_LT(driven_off_m, 1e-6);
}

}  // namespace
}  // namespace pcisim::modeling
