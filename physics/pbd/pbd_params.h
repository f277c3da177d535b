#pragma once
// The accuracy knobs of a PBD step. Substeps and iterations are separate: a substep repeats
// predict-project-update with dt/substeps, an iteration is one more pass over the constraints.
#include <Eigen/Core>

namespace pcisim::physics::pbd {

enum class SolverKind {
  kGaussSeidel,  // each constraint moves its particles at once (sequential)
  kJacobi,       // all constraints of a group read the same positions; corrections averaged (parallel)
  // kJacobi on a CUDA device (PbdCudaSolver, built on first use); the same answer to summation
  // order. PbdSystem::step throws std::invalid_argument naming it when built without CUDA or
  // when no device can be used. See docs/pbd.md "CUDA Jacobi".
  kJacobiCuda,
};

// how Jacobi shares corrections among constraints that touch the same particle
enum class JacobiAveraging {
  // soft-tissue paper eq 7: each particle divides its summed corrections by its own count n_i.
  // The ends of a constraint can get different shares, so momentum is kept only approximately.
  kPerParticle,
  // each constraint's corrections are divided by the largest count among its particles: every
  // constraint's impulse stays balanced, so linear and angular momentum are kept as in
  // Gauss-Seidel; never moves a particle further than kPerParticle does
  kPerConstraint,
};

struct PbdParams {
  int substeps = 1;
  int iterations = 10;
  SolverKind solver = SolverKind::kGaussSeidel;
  // Jacobi successive over-relaxation: x += w * sum(dx) / n, w in [1, 2] (soft-tissue paper eq 7);
  // every iteration but the last of a substep (see PbdSystem::step)
  double sor_w = 1.0;
  JacobiAveraging averaging = JacobiAveraging::kPerParticle;
  Eigen::Vector3d gravity_m_per_s2 = Eigen::Vector3d::Zero();
  // velocity drag, applied as v /= (1 + c dt) so that any dt stays stable
  double damping_per_s = 0.0;
};

}  // namespace pcisim::physics::pbd
