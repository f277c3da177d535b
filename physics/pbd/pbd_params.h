#pragma once
// The accuracy knobs of a PBD step. Substeps and iterations are separate: a substep repeats
// predict-project-update with dt/substeps, an iteration is one more pass over the constraints.
#include <Eigen/Core>

namespace pcisim::physics::pbd {

enum class SolverKind {
  kGaussSeidel,  // each constraint moves its particles at once (sequential)
  kJacobi,       // all constraints of a group read the same positions; corrections averaged (parallel)
};

struct PbdParams {
  int substeps = 1;
  int iterations = 10;
  SolverKind solver = SolverKind::kGaussSeidel;
  // Jacobi successive over-relaxation: x += w * sum(dx) / n, w in [1, 2] (soft-tissue paper eq 7);
  // every iteration but the last of a substep (see PbdSystem::step)
  double sor_w = 1.0;
  Eigen::Vector3d gravity_m_per_s2 = Eigen::Vector3d::Zero();
  // velocity drag, applied as v /= (1 + c dt) so that any dt stays stable
  double damping_per_s = 0.0;
};

}  // namespace pcisim::physics::pbd
