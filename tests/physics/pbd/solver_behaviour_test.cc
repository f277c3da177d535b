// What the step promises: clustered shape matching restores the rest shape, driven particles
// follow their trajectories exactly, XPBD stiffness does not depend on the iteration count,
// and the Jacobi solver with SOR reaches the same answer as Gauss-Seidel.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "physics/pbd/pbd_system.h"
#include "physics/pbd/procedural_ventricle.h"
#include "tests/physics/pbd/pbd_test_bodies.h"

namespace pcisim::physics::pbd {
namespace {

using namespace testing;

TEST(ClusteredShapeMatching, RecoversTheRestShapeAfterALargeDeformation) {
  for (SolverKind solver : {SolverKind::kGaussSeidel, SolverKind::kJacobi}) {
    BlockSpec s;
    s.n = 5;
    s.springs = false;  // the clusters alone
    s.cluster_compliance_s2 = 0.0;
    PbdSystem sys = block(s);
    const Eigen::Matrix3Xd rest = sys.particles().position_m;
    // squash to a fifth of its height, shear it and twist the top by 90 deg
    auto& x = sys.particles().position_m;
    for (int i = 0; i < x.cols(); ++i) {
      const double z = x(2, i);
      const Eigen::Matrix3d twist =
          Eigen::AngleAxisd(z / 0.04 * std::numbers::pi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      x.col(i) = twist * Eigen::Vector3d(x(0, i) + 0.5 * z, x(1, i), 0.2 * z);
    }
    ASSERT_GT(shape_error_m(rest, x), 0.02) << "a large deformation";
    PbdParams params;
    params.solver = solver;
    params.sor_w = 1.5;
    params.iterations = 10;
    params.damping_per_s = 5.0;
    for (int step = 0; step < 240; ++step) sys.step(1.0 / 60.0, params);
    EXPECT_LT(shape_error_m(rest, sys.particles().position_m), 1e-4)
        << (solver == SolverKind::kJacobi ? "jacobi" : "gs");
  }
}

TEST(DrivenParticles, FollowTheirTrajectoriesExactly) {
  VentricleSpec spec;
  spec.spacing_m = 0.006;
  Ventricle v = build_ventricle(spec);
  ASSERT_FALSE(v.driven.empty());
  PbdParams params;
  params.substeps = 3;
  params.iterations = 4;
  params.gravity_m_per_s2 = {0, 0, -9.81};
  const double dt = 1.0 / 30.0;
  for (int step = 1; step <= 45; ++step) {
    const double t = step * dt;
    for (int i : v.driven) {
      const Eigen::Vector3d r0 = v.rest_m.col(i);
      // a beating wall: radial contraction plus a small lift, 1.2 Hz
      const double squeeze = 0.15 * 0.5 * (1.0 - std::cos(2.0 * std::numbers::pi * 1.2 * t));
      v.system.set_driven_target(
          i, Eigen::Vector3d(r0.x() * (1.0 - squeeze), r0.y() * (1.0 - squeeze), r0.z() + 0.01 * squeeze));
    }
    const Eigen::Matrix3Xd before = v.system.particles().position_m;
    v.system.step(dt, params);
    for (int i : v.driven) {
      const Eigen::Vector3d r0 = v.rest_m.col(i);
      const double squeeze = 0.15 * 0.5 * (1.0 - std::cos(2.0 * std::numbers::pi * 1.2 * t));
      const Eigen::Vector3d want(r0.x() * (1.0 - squeeze), r0.y() * (1.0 - squeeze), r0.z() + 0.01 * squeeze);
      ASSERT_EQ(v.system.particles().position_m.col(i), want) << "particle " << i << " step " << step;
      // velocity of the last substep: a third of the step's straight-line motion
      EXPECT_LT((v.system.particles().velocity_m_per_s.col(i) - (want - before.col(i)) / dt).norm(), 1e-9);
    }
  }
  // the free particles were dragged along, and nothing else broke
  EXPECT_TRUE(all_finite(v.system));
  EXPECT_GT(shape_error_m(v.rest_m, v.system.particles().position_m), 1e-4);
}

// a chain hanging from a pinned top; analytic static stretch of link k: alpha * m g * (particles below)
double hanging_chain_stretch(int iterations, SolverKind solver, double sor_w, int substeps,
                             JacobiAveraging averaging = JacobiAveraging::kPerParticle) {
  constexpr int n = 10;
  constexpr double mass = 0.01, spacing = 0.01, alpha = 1e-3;
  PbdSystem sys;
  for (int i = 0; i < n; ++i) sys.add_particle(Eigen::Vector3d(0, 0, -spacing * i), mass);
  sys.pin(0);
  for (int i = 0; i + 1 < n; ++i) sys.add_distance(i, i + 1, alpha);
  sys.finalize();
  PbdParams params;
  params.iterations = iterations;
  params.substeps = substeps;
  params.solver = solver;
  params.sor_w = sor_w;
  params.averaging = averaging;
  params.gravity_m_per_s2 = {0, 0, -9.81};
  params.damping_per_s = 4.0;
  for (int step = 0; step < 900; ++step) sys.step(1.0 / 60.0, params);
  return -sys.particles().position_m(2, n - 1) - spacing * (n - 1);
}

TEST(Xpbd, StaticStretchDoesNotDependOnIterations) {
  const double analytic = 1e-3 * 0.01 * 9.81 * 45.0;  // sum over links of the weight below
  // 10 substeps: alpha/h^2 is then comparable to 1/m, where a few iterations converge a substep
  const double few = hanging_chain_stretch(5, SolverKind::kGaussSeidel, 1.0, 10);
  const double many = hanging_chain_stretch(50, SolverKind::kGaussSeidel, 1.0, 10);
  EXPECT_NEAR(many, analytic, 0.02 * analytic);
  EXPECT_NEAR(few, many, 0.05 * many) << "5 iterations " << few << " m, 50 iterations " << many << " m";
  // and not on the substeps either
  EXPECT_NEAR(hanging_chain_stretch(50, SolverKind::kGaussSeidel, 1.0, 20), analytic, 0.02 * analytic);
}

TEST(Xpbd, JacobiWithSorReachesTheSameStretch) {
  const double analytic = 1e-3 * 0.01 * 9.81 * 45.0;
  for (double w : {1.0, 1.5, 1.9}) {
    EXPECT_NEAR(hanging_chain_stretch(50, SolverKind::kJacobi, w, 10), analytic, 0.03 * analytic) << "w " << w;
    EXPECT_NEAR(hanging_chain_stretch(50, SolverKind::kJacobi, w, 10, JacobiAveraging::kPerConstraint), analytic,
                0.03 * analytic)
        << "per-constraint averaging, w " << w;
  }
}

TEST(Jacobi, OverRelaxationConvergesFasterOnAStiffBody) {
  // the residual after a fixed budget of iterations: w = 1.5 beats plain averaging
  auto residual = [](double w) {
    BlockSpec s;
    s.n = 5;
    s.spring_compliance_m_per_n = 0.0;
    s.clusters = false;
    s.pin_top = true;
    PbdSystem sys = block(s);
    PbdParams params;
    params.solver = SolverKind::kJacobi;
    params.sor_w = w;
    params.iterations = 10;
    params.gravity_m_per_s2 = {0, 0, -9.81};
    for (int step = 0; step < 30; ++step) sys.step(1.0 / 60.0, params);
    return max_strain(sys);
  };
  const double plain = residual(1.0), sor = residual(1.5);
  EXPECT_TRUE(std::isfinite(sor));
  EXPECT_LT(sor, plain);
}

TEST(Jacobi, OverRelaxationNeverHandsAnOvershootToTheVelocities) {
  // one or three iterations at w = 1.9 would leave x* beyond a stiff constraint every substep;
  // fed into the velocities that grows without bound unless the last iteration is not
  // over-relaxed. A pendulum: one rigid link, so nothing averages the overshoot away.
  for (int iterations : {1, 3}) {
    PbdSystem sys;
    sys.add_particle(Eigen::Vector3d(0, 0, 0), 0.01);
    sys.add_particle(Eigen::Vector3d(0.05, 0, 0), 0.01);
    sys.pin(0);
    sys.add_distance(0, 1, 0.0);
    sys.finalize();
    PbdParams params;
    params.solver = SolverKind::kJacobi;
    params.sor_w = 1.9;
    params.iterations = iterations;
    params.substeps = 4;
    params.gravity_m_per_s2 = {0, 0, -9.81};
    params.damping_per_s = 1.0;
    for (int step = 0; step < 300; ++step) sys.step(1.0 / 30.0, params);
    ASSERT_TRUE(all_finite(sys));
    EXPECT_LT(max_abs_coordinate_m(sys), 0.1) << iterations << " iterations";
    EXPECT_LT(max_strain(sys), 0.01) << iterations << " iterations";
  }
}

}  // namespace
}  // namespace pcisim::physics::pbd
