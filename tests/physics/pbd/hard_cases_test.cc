// Hard cases (DESIGN.md): each asserts no NaN, bounded positions, bounded constraint error, and
// recovery once the provocation stops.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "physics/pbd/pbd_system.h"
#include "physics/pbd/procedural_ventricle.h"
#include "tests/physics/pbd/pbd_test_bodies.h"

namespace pcisim::physics::pbd {
namespace {

using namespace testing;

constexpr double kDt = 1.0 / 60.0;

PbdParams hanging_params() {
  PbdParams p;
  p.substeps = 2;
  p.iterations = 8;
  p.gravity_m_per_s2 = {0, 0, -9.81};
  p.damping_per_s = 3.0;
  return p;
}

BlockSpec hanging_block() {
  BlockSpec s;
  s.pin_top = true;
  return s;
}

// the undisturbed body at rest under gravity: what recovery must return to
Eigen::Matrix3Xd equilibrium(const BlockSpec& s, const PbdParams& params = hanging_params()) {
  PbdSystem sys = block(s);
  for (int step = 0; step < 600; ++step) sys.step(kDt, params);
  return sys.particles().position_m;
}

void expect_sane(const PbdSystem& sys, double bound_m, double strain_bound, const char* what) {
  ASSERT_TRUE(all_finite(sys)) << what;
  EXPECT_LT(max_abs_coordinate_m(sys), bound_m) << what;
  EXPECT_LT(max_strain(sys), strain_bound) << what;
}

double max_distance_m(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
  return (a - b).colwise().norm().maxCoeff();
}

TEST(HardCases, TimeStepTimesTen) {
  const BlockSpec s = hanging_block();
  for (SolverKind solver : {SolverKind::kGaussSeidel, SolverKind::kJacobi}) {
    PbdParams p = hanging_params();
    p.solver = solver;
    p.sor_w = 1.9;
    const Eigen::Matrix3Xd rest_state = equilibrium(s, p);
    PbdSystem sys = block(s);
    for (int step = 0; step < 100; ++step) {
      sys.step(10.0 * kDt, p);
      expect_sane(sys, 1.0, 1.0, "dt x10");
    }
    for (int step = 0; step < 600; ++step) sys.step(kDt, p);
    expect_sane(sys, 1.0, 0.5, "after");
    EXPECT_LT(max_distance_m(sys.particles().position_m, rest_state), 1e-4);
  }
}

TEST(HardCases, BeatingVentricleAtTenTimesTheStep) {
  // the heart's configuration (springs, clusters, a driven wall) beating with dt = 1/3 s
  for (int variant = 0; variant < 3; ++variant) {
    VentricleSpec spec;
    spec.spacing_m = 0.006;
    Ventricle v = build_ventricle(spec);
    PbdParams p;
    p.iterations = 2;
    p.solver = variant == 0 ? SolverKind::kGaussSeidel : SolverKind::kJacobi;
    p.sor_w = 1.9;
    p.averaging = variant == 2 ? JacobiAveraging::kPerConstraint : JacobiAveraging::kPerParticle;
    p.damping_per_s = 5.0;
    const double dt = 10.0 / 30.0;
    for (int step = 1; step <= 30; ++step) {
      const double s = 0.15 * 0.5 * (1.0 - std::cos(2.0 * std::numbers::pi * 1.2 * step * dt));
      for (int i : v.driven)
        v.system.set_driven_target(i,
                                   Eigen::Vector3d(v.rest_m(0, i) * (1 - s), v.rest_m(1, i) * (1 - s), v.rest_m(2, i)));
      v.system.step(dt, p);
      expect_sane(v.system, 0.2, 1.0, "beating at dt x10");
    }
    // the wall stops at rest; at the normal step the body returns to its rest shape
    for (int i : v.driven) v.system.set_driven_target(i, v.rest_m.col(i));
    for (int step = 0; step < 300; ++step) v.system.step(1.0 / 30.0, p);
    EXPECT_LT(max_distance_m(v.system.particles().position_m, v.rest_m), 1e-4) << "variant " << variant;
    EXPECT_EQ(v.system.quarantined_total(), 0);
  }
}

TEST(HardCases, StiffnessAndMassRatiosOfAThousand) {
  BlockSpec s = hanging_block();
  s.n = 4;
  std::vector<double> mass(s.n * s.n * s.n, s.mass_kg);
  for (size_t i = 0; i < mass.size(); i += 2) mass[i] *= 1000.0;  // every other particle 1000x heavier
  // built by hand: the springs alternate between soft and 1000x stiffer
  PbdSystem mixed;
  const int n = s.n;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int id = block_index(n, i, j, k);
        mixed.add_particle(s.spacing_m * Eigen::Vector3d(i, j, k), mass[id]);
        if (k == n - 1) mixed.pin(id);
      }
  int count = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (int o = 0; o < 3; ++o) {
          const int ii = i + (o == 0), jj = j + (o == 1), kk = k + (o == 2);
          if (ii < n && jj < n && kk < n)
            mixed.add_distance(block_index(n, i, j, k), block_index(n, ii, jj, kk), (count++ % 2) ? 1e-3 : 1e-6);
        }
  // clusters give the lattice its shear stiffness (springs along lattice edges alone are a mechanism)
  Eigen::Matrix3Xd rest(3, n * n * n);
  for (int i = 0; i < n * n * n; ++i) rest.col(i) = s.spacing_m * Eigen::Vector3d(i % n, (i / n) % n, i / (n * n));
  for (const auto& c : grid_clusters(rest, s.cluster_cube_m, s.cluster_overlap))
    mixed.add_cluster(c, s.cluster_compliance_s2);
  mixed.finalize();
  PbdParams p = hanging_params();
  double worst = 0.0;
  for (int step = 0; step < 600; ++step) {
    mixed.step(kDt, p);
    ASSERT_TRUE(all_finite(mixed));
    worst = std::max(worst, max_strain(mixed));
  }
  EXPECT_LT(max_abs_coordinate_m(mixed), 1.0);
  // heavy particles on soft springs sag, but the body neither explodes nor tears
  EXPECT_LT(worst, 3.0);
  // recovery: gravity off, the body returns to its rest shape
  p.gravity_m_per_s2.setZero();
  for (int step = 0; step < 1200; ++step) mixed.step(kDt, p);
  EXPECT_LT(max_strain(mixed), 1e-3);
}

TEST(HardCases, InvertedBodyTurnsRightSideOut) {
  // local clusters plus one global cluster, as the heart paper pairs them: the global cluster
  // decides which way the body un-inverts, so the local ones cannot lock into a tangle
  BlockSpec s;
  s.n = 4;
  s.cluster_cube_m = 0.015;
  PbdSystem sys = block_unfinalized(s);
  std::vector<int> all(s.n * s.n * s.n);
  for (int i = 0; i < static_cast<int>(all.size()); ++i) all[i] = i;
  sys.add_cluster(all, 1e-3);
  sys.finalize();
  const Eigen::Matrix3Xd rest = sys.particles().position_m;
  // mirrored through z = 15 mm (every cluster inverted) and squashed in x
  for (int i = 0; i < rest.cols(); ++i) {
    sys.particles().position_m(2, i) = 0.030 - rest(2, i);
    sys.particles().position_m(0, i) = 0.6 * rest(0, i);
  }
  PbdParams p;
  p.iterations = 8;
  p.damping_per_s = 4.0;
  for (int step = 0; step < 60; ++step) {
    sys.step(kDt, p);
    expect_sane(sys, 1.0, 1.0, "inverted");
  }
  for (int step = 0; step < 300; ++step) sys.step(kDt, p);
  EXPECT_LT(shape_error_m(rest, sys.particles().position_m), 1e-4) << "rest shape up to a rigid motion";
  EXPECT_LT(max_strain(sys), 1e-3);
}

TEST(HardCases, AllParticlesOfAClusterCoincident) {
  BlockSpec s;
  s.n = 3;
  s.cluster_cube_m = 0.03;  // one cluster holds every particle
  PbdSystem sys = block(s);
  ASSERT_EQ(sys.clusters().count(), 1);
  const Eigen::Matrix3Xd rest = sys.particles().position_m;
  sys.particles().position_m.colwise() = Eigen::Vector3d(0.1, 0.2, 0.3);
  PbdParams p;
  p.iterations = 8;
  p.damping_per_s = 4.0;
  for (int step = 0; step < 60; ++step) {
    sys.step(kDt, p);
    ASSERT_TRUE(all_finite(sys));
    EXPECT_LT(max_abs_coordinate_m(sys), 1.0);
  }
  for (int step = 0; step < 300; ++step) sys.step(kDt, p);
  EXPECT_LT(shape_error_m(rest, sys.particles().position_m), 1e-4);
  EXPECT_LT(max_strain(sys), 1e-3);
}

TEST(HardCases, NanInOneParticleIsQuarantinedNotSpread) {
  const BlockSpec s = hanging_block();
  for (SolverKind solver : {SolverKind::kGaussSeidel, SolverKind::kJacobi}) {
    PbdSystem sys = block(s);
    PbdParams p = hanging_params();
    p.solver = solver;
    p.sor_w = 1.5;
    // with few iterations the rest state depends on the solver: compare like with like
    const Eigen::Matrix3Xd rest_state = equilibrium(s, p);
    for (int step = 0; step < 30; ++step) sys.step(kDt, p);
    const int victim = 5;
    const Eigen::Vector3d last = sys.particles().position_m.col(victim);
    sys.particles().position_m(1, victim) = std::numeric_limits<double>::quiet_NaN();
    sys.particles().velocity_m_per_s(2, 9) = std::numeric_limits<double>::infinity();
    for (int step = 0; step < 120; ++step) {
      sys.step(kDt, p);
      expect_sane(sys, 1.0, 1.0, "quarantined");
    }
    EXPECT_EQ(sys.quarantined_total(), 2);
    EXPECT_EQ(sys.quarantined_now(), 2);
    EXPECT_EQ(sys.particles().position_m.col(victim), last) << "frozen at its last finite position";
    EXPECT_EQ(sys.particles().state[victim], ParticleState::kQuarantined);
    // the provocation is over: released, the body settles where it would have
    sys.release_quarantine();
    for (int step = 0; step < 600; ++step) sys.step(kDt, p);
    EXPECT_EQ(sys.quarantined_now(), 0);
    EXPECT_LT(max_distance_m(sys.particles().position_m, rest_state), 1e-3);
  }
}

TEST(HardCases, NonFiniteDrivenTargetFreezesThatParticleOnly) {
  PbdSystem sys;
  for (int i = 0; i < 4; ++i) sys.add_particle(Eigen::Vector3d(0.01 * i, 0, 0), 0.01);
  for (int i = 0; i + 1 < 4; ++i) sys.add_distance(i, i + 1, 0.0);
  sys.drive(0);
  sys.finalize();
  sys.set_driven_target(0, Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0));
  sys.step(kDt, PbdParams{});
  EXPECT_TRUE(all_finite(sys));
  EXPECT_EQ(sys.quarantined_total(), 1);
  EXPECT_EQ(sys.particles().position_m.col(0), Eigen::Vector3d(0, 0, 0));

  // a finite target again and the quarantine released: the particle is driven, not free, and
  // arrives exactly where it is told; a pinned particle stays pinned through the same cycle
  sys.set_driven_target(0, Eigen::Vector3d(-0.005, 0.002, 0));
  sys.release_quarantine();
  EXPECT_EQ(sys.particles().state[0], ParticleState::kDriven);
  EXPECT_EQ(sys.particles().inv_mass_per_kg[0], 0.0);
  sys.step(kDt, PbdParams{});
  EXPECT_EQ(sys.particles().position_m.col(0), Eigen::Vector3d(-0.005, 0.002, 0));
  EXPECT_EQ(sys.quarantined_now(), 0);
}

TEST(HardCases, ReleasedPinnedParticleIsPinnedAgain) {
  PbdSystem sys;
  for (int i = 0; i < 3; ++i) sys.add_particle(Eigen::Vector3d(0.01 * i, 0, 0), 0.01);
  sys.add_distance(0, 1, 0.0);
  sys.add_distance(1, 2, 0.0);
  sys.pin(0);
  sys.finalize();
  sys.particles().position_m(0, 0) = std::numeric_limits<double>::quiet_NaN();  // the caller broke it
  PbdParams p;
  p.gravity_m_per_s2 = Eigen::Vector3d(0, 0, -9.81);
  sys.step(kDt, p);
  EXPECT_EQ(sys.particles().state[0], ParticleState::kQuarantined);
  sys.release_quarantine();
  EXPECT_EQ(sys.particles().state[0], ParticleState::kPinned);
  for (int step = 0; step < 60; ++step) sys.step(kDt, p);
  EXPECT_EQ(sys.particles().position_m.col(0), Eigen::Vector3d(0, 0, 0)) << "held against gravity";
  EXPECT_LT(sys.particles().position_m(2, 2), -0.005) << "the rest hangs from it";
}

TEST(HardCases, DrivenTargetForAParticleThatIsNotDrivenIsRefusedByIndex) {
  PbdSystem sys;
  sys.add_particle(Eigen::Vector3d::Zero(), 0.01);
  sys.add_particle(Eigen::Vector3d::UnitX(), 0.01);
  sys.drive(1);
  EXPECT_THROW(sys.set_driven_target(1, Eigen::Vector3d::Zero()), std::logic_error) << "before finalize";
  sys.finalize();
  try {
    sys.set_driven_target(0, Eigen::Vector3d::Zero());
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("particle 0"), std::string::npos) << e.what();
  }
  EXPECT_THROW(sys.set_driven_target(7, Eigen::Vector3d::Zero()), std::invalid_argument);
  EXPECT_NO_THROW(sys.set_driven_target(1, Eigen::Vector3d::Zero()));
}

TEST(HardCases, LongRunOfADampedOscillatingBody) {
  // 1e5 steps of a soft body set ringing: energy never grows, positions stay put, it comes to rest
  BlockSpec s;
  s.n = 3;
  s.spring_compliance_m_per_n = 1e-2;
  s.cluster_cube_m = 0.03;
  s.cluster_compliance_s2 = 1e-3;
  PbdSystem sys = block(s);
  const Eigen::Matrix3Xd rest = sys.particles().position_m;
  for (int i = 0; i < rest.cols(); ++i) sys.particles().position_m(2, i) *= 1.5;  // stretched 50 %
  PbdParams p;
  p.iterations = 4;
  p.damping_per_s = 0.05;
  const double e0 = spring_energy_j(sys) + cluster_energy_j(sys);
  ASSERT_GT(e0, 0.0);
  double e_max = 0.0;
  for (int step = 0; step < 100000; ++step) {
    sys.step(kDt, p);
    if (step % 100 == 0) {
      ASSERT_TRUE(all_finite(sys)) << "step " << step;
      ASSERT_LT(max_abs_coordinate_m(sys), 0.1) << "step " << step;
      e_max = std::max(e_max, kinetic_energy_j(sys) + spring_energy_j(sys) + cluster_energy_j(sys));
    }
  }
  EXPECT_LT(e_max, 1.01 * e0 + 1e-12) << "no energy from nowhere";
  EXPECT_LT(shape_error_m(rest, sys.particles().position_m), 1e-5);
  EXPECT_LT(kinetic_energy_j(sys), 1e-6 * e0);
  EXPECT_LT((linear_momentum(sys)).norm(), 1e-12);
}

}  // namespace
}  // namespace pcisim::physics::pbd
