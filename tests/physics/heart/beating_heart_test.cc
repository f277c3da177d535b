// BeatingHeart in ordinary use: the template heart built into particles and springs, driven
// particles exactly on the sequence, free particles smooth and bounded, periodic, no allocation.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "physics/heart/beating_heart.h"
#include "anatomy/heart/heart_frame.h"
#include "anatomy/heart/heart_motion.h"
#include "anatomy/heart/synthetic_heart_motion.h"
#include "realtime/allocation_count.h"
#include "tests/physics/heart/heart_health.h"

namespace pcisim::physics {
namespace {

using Eigen::Vector3d;
using testing::health;
using testing::HeartHealth;

std::string construct_error(const HeartBeatParams& p) {
  try {
    BeatingHeart h(p);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

TEST(HeartBeating, BuildsTheTemplate) {
  const BeatingHeart h(HeartBeatParams{});
  const int n = h.system().particle_count();
  EXPECT_GE(n, 800);
  EXPECT_LE(n, 2000);
  EXPECT_EQ(static_cast<int>(h.driven().size() + h.free_particles().size()), n);
  EXPECT_GT(h.free_particles().size(), 100u);  // atria and aortic root
  EXPECT_GT(h.driven().size(), h.free_particles().size());
  double mass_kg = h.system().particles().mass_kg.sum();
  EXPECT_GT(mass_kg, 0.3);  // adult heart ~0.3-0.5 kg; this one is a 100 mm ball plus atria
  EXPECT_LT(mass_kg, 0.7);
  // the epicardium is closed, outward and encloses the whole heart
  double enclosed_m3 = 0;
  const Eigen::Matrix3Xd& x = h.rest_positions_m();
  for (const auto& t : h.epicardium()) enclosed_m3 += x.col(t[0]).dot(x.col(t[1]).cross(x.col(t[2]))) / 6;
  EXPECT_GT(enclosed_m3, 0.5e-3);
  EXPECT_EQ(h.system().clusters().count(), 1);
  EXPECT_EQ(h.system().clusters().end(0) - h.system().clusters().begin(0), n);
  EXPECT_GT(h.system().bending_constraints().size(), 100u);
  EXPECT_DOUBLE_EQ(h.phase(), 0.0);
  // at rest every spring is at its rest length
  EXPECT_LT(health(h).max_strain, 1e-12);
}

TEST(HeartBeating, ParamsAreCheckedByName) {
  HeartBeatParams p;
  p.rate_bpm = 0;
  EXPECT_EQ(construct_error(p).rfind("heart_beat.rate_bpm must be in [20, 250], got 0", 0), 0u) << construct_error(p);
  p = {};
  p.iterations = 0;
  EXPECT_EQ(construct_error(p).rfind("heart_beat.iterations", 0), 0u);
  p = {};
  p.sor_w = 2.5;
  EXPECT_EQ(construct_error(p).rfind("heart_beat.sor_w", 0), 0u);
  p = {};
  p.stretch_compliance_m_per_n = NAN;
  EXPECT_EQ(construct_error(p).rfind("heart_beat.stretch_compliance_m_per_n", 0), 0u);
  p = {};
  p.cluster_size_m = 1e-5;  // a hundred million cubes over the heart: refused, not attempted
  EXPECT_EQ(construct_error(p).rfind("heart_beat.cluster_size_m", 0), 0u) << construct_error(p);
  p.cluster_size_m = NAN;
  EXPECT_EQ(construct_error(p).rfind("heart_beat.cluster_size_m", 0), 0u);
  p = {};
  p.motion_file = "/nonexistent.motion";
  EXPECT_EQ(construct_error(p), "heart_beat.motion_file: /nonexistent.motion: cannot open");
  // a tissue scaling that returns nonsense is refused naming the particle and where it is
  for (const auto& scaling : {HeartTissueScaling{[](const Vector3d&) { return 0.0; }, {}},
                              HeartTissueScaling{{}, [](const Vector3d&) { return NAN; }}}) {
    try {
      BeatingHeart bad(HeartBeatParams{}, scaling);
      ADD_FAILURE() << "no error";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("heart particle 0 at (", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find("scale must be finite"), std::string::npos) << e.what();
    }
  }
  BeatingHeart h(HeartBeatParams{});
  EXPECT_THROW(h.set_rate_bpm(-1), std::invalid_argument);
  EXPECT_DOUBLE_EQ(h.params().rate_bpm, 72.0);
}

TEST(HeartBeating, DrivenParticlesFollowTheSequenceExactly) {
  BeatingHeart h(HeartBeatParams{});
  const double dt = 1.0 / 30;
  double checked_phases = 0;
  for (int k = 0; k < 60; ++k) {
    h.step(dt);
    EXPECT_NEAR(h.phase(), std::fmod((k + 1) * dt * 72.0 / 60.0, 1.0), 1e-12);
    if (k % 7 != 0) continue;
    ++checked_phases;
    double worst = 0;
    for (int i : h.driven()) {
      const Vector3d want =
          h.rest_positions_m().col(i) + h.motion().displacement_m(h.rest_positions_m().col(i), h.phase());
      worst = std::max(worst, (h.positions_m().col(i) - want).norm());
    }
    EXPECT_LT(worst, 1e-12) << "phase " << h.phase();
  }
  EXPECT_GE(checked_phases, 8);
}

TEST(HeartBeating, FreeParticlesStayBoundedAndSmooth) {
  BeatingHeart h(HeartBeatParams{});
  const double dt = 1.0 / 60;
  const int steps = static_cast<int>(std::round(2 * 60.0 / 72.0 / dt));  // two cycles
  Eigen::Matrix3Xd prev = h.positions_m(), prev2 = prev;
  HeartHealth worst;
  double max_second_difference_m = 0, max_speed = 0, max_driven_speed = 0;
  for (int k = 0; k < steps; ++k) {
    h.step(dt);
    worst.merge(health(h));
    const auto& v = h.system().particles().velocity_m_per_s;
    for (int i : h.free_particles()) {
      if (k >= 1)
        max_second_difference_m =
            std::max(max_second_difference_m, (h.positions_m().col(i) - 2 * prev.col(i) + prev2.col(i)).norm());
      max_speed = std::max(max_speed, v.col(i).norm());
    }
    for (int i : h.driven())
      max_driven_speed = std::max(max_driven_speed, (h.positions_m().col(i) - prev.col(i)).norm() / dt);
    prev2 = prev;
    prev = h.positions_m();
  }
  std::printf("free: max from rest %.2f mm, speed %.1f mm/s (driven %.1f mm/s), 2nd difference %.3f mm, strain %.3f\n",
              worst.max_free_from_rest_m * 1e3, max_speed * 1e3, max_driven_speed * 1e3, max_second_difference_m * 1e3,
              worst.max_strain);
  EXPECT_TRUE(worst.finite);
  // the atria ride on the descending base: they move, by about as much as the base does
  EXPECT_GT(worst.max_free_from_rest_m, 1e-3);
  EXPECT_LT(worst.max_free_from_rest_m, 15e-3);
  // no faster than the driven tissue they hang on, and smooth (no step-to-step jerks)
  EXPECT_LT(max_speed, 1.5 * max_driven_speed);
  EXPECT_LT(max_second_difference_m, 0.5e-3);
  EXPECT_LT(worst.max_strain, 0.3);
}

TEST(HeartBeating, AFullCycleReturnsNearTheStart) {
  BeatingHeart h(HeartBeatParams{});
  const double dt = 60.0 / 72.0 / 25;  // 25 steps per cycle
  for (int k = 0; k < 25; ++k) h.step(dt);
  const Eigen::Matrix3Xd after_one = h.positions_m();
  for (int k = 0; k < 50; ++k) h.step(dt);
  EXPECT_LT(std::min(h.phase(), 1.0 - h.phase()), 1e-9);
  double driven = 0, free_from_rest = 0, free_cycle_to_cycle = 0;
  for (int i : h.driven()) driven = std::max(driven, (h.positions_m().col(i) - h.rest_positions_m().col(i)).norm());
  for (int i : h.free_particles()) {
    free_from_rest = std::max(free_from_rest, (h.positions_m().col(i) - h.rest_positions_m().col(i)).norm());
    free_cycle_to_cycle = std::max(free_cycle_to_cycle, (h.positions_m().col(i) - after_one.col(i)).norm());
  }
  std::printf("after 3 cycles: driven %.2g m from rest, free %.3f mm from rest, %.4f mm from cycle 1\n", driven,
              free_from_rest * 1e3, free_cycle_to_cycle * 1e3);
  EXPECT_LT(driven, 1e-6);  // the sequence's end-diastole is the rest shape (float32 samples)
  EXPECT_LT(free_from_rest, 1e-3);
  EXPECT_LT(free_cycle_to_cycle, 0.1e-3);  // periodic: the beat repeats
}

TEST(HeartBeating, StepAllocatesNothing) {
  for (pbd::SolverKind solver : {pbd::SolverKind::kJacobi, pbd::SolverKind::kGaussSeidel}) {
    HeartBeatParams p;
    p.solver = solver;
    BeatingHeart h(p);
    h.step(1.0 / 30);
    long allocations = -1;
    {
      pcisim::realtime::AllocationCount count;
      for (int k = 0; k < 30; ++k) h.step(1.0 / 30);
      h.set_rate_bpm(90);
      for (int k = 0; k < 5; ++k) h.step(1.0 / 30);
      allocations = count.allocations();
    }
    EXPECT_EQ(allocations, 0) << "solver " << static_cast<int>(solver);
  }
}

TEST(HeartBeating, ReadsAMotionFile) {
  const auto path = std::filesystem::temp_directory_path() / "pcisim_beating_heart_test.motion";
  anatomy::SyntheticMotionSpec spec;
  spec.twist_deg = 0;  // a different sequence from the built-in one
  anatomy::make_synthetic_heart_motion(spec).write(path.string());
  HeartBeatParams p;
  p.motion_file = path.string();
  BeatingHeart from_file(p);
  std::filesystem::remove(path);
  const anatomy::HeartMotion want = anatomy::make_synthetic_heart_motion(spec);
  for (int k = 0; k < 10; ++k) from_file.step(1.0 / 30);
  double worst = 0;
  for (int i : from_file.driven()) {
    const Vector3d r = from_file.rest_positions_m().col(i);
    worst = std::max(worst, (from_file.positions_m().col(i) - r - want.displacement_m(r, from_file.phase())).norm());
  }
  EXPECT_LT(worst, 1e-12);
}

}  // namespace
}  // namespace pcisim::physics
