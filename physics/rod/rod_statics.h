#pragma once
// The static equilibrium of a CosseratRod under its node forces and gravity, by Newton's method
// on the rod's discrete energy (the same strains as the XPBD constraints, cosserat_constraints.h):
//   U = sum_segments 1/2 l Gamma^T diag(GA, GA, EA) Gamma + sum_pairs 1/2 l_b Omega^T diag(EI, EI, GJ) Omega
//       - sum_nodes (f_i + m_i g) . x_i
// Unknowns: the free nodes' positions and a rotation vector per segment (q <- q exp(phi / 2),
// material frame). Each term's gradient and Hessian come from central differences of that
// term alone (at most 9 unknowns each), assembled into a sparse banded matrix and solved by
// LDL^T; loads are applied in steps with a backtracking line search on U.
//
// Why: XPBD with a few Gauss-Seidel sweeps per substep does not converge the stiff constraints
// of a slender rod (its static sag depends on iterations and substeps), so the analytic tests
// check the discrete model's equilibrium with this solver, and the dynamic XPBD step separately
// against it. A test and bench tool, not for the real-time loop: it allocates.
#include "physics/rod/cosserat_rod.h"

namespace pcisim::physics::rod {

struct StaticSolveOptions {
  int load_steps = 10;             // the loads are ramped in this many equal steps
  int max_newton_iterations = 60;  // per load step
  double step_tolerance = 1e-9;    // stop when the largest Newton update is below this x length
};

struct StaticSolveResult {
  bool converged = false;
  int newton_iterations = 0;  // over all load steps
  double energy_j = 0.0;      // U at the solution
};

// moves rod's nodes and orientations to the equilibrium (from their current state) and zeroes
// nothing else; velocities are left as they were
StaticSolveResult solve_static(CosseratRod& rod, const StaticSolveOptions& options = {});

// U of the rod's current state (as above), joules
double rod_energy_j(const CosseratRod& rod, double load_scale = 1.0);

}  // namespace pcisim::physics::rod
