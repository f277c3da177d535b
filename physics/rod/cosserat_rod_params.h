#pragma once
// Parameters of the discrete Cosserat rod (Kugelstadt & Schoemer 2016, "Position and
// orientation based Cosserat rods"). Stiffnesses are the section products (E I, G J, E A, G A)
// so a wire's datasheet figures go in directly; the constraints' compliances follow from them
// and the segment length (cosserat_constraints.h). Defaults: the order of magnitude of a
// 0.014-inch steel-core coronary wire (core 0.3 mm, E 200 GPa, G 77 GPa), not a cited preset.
#include <Eigen/Core>

namespace pcisim::physics::rod {

// how each substep's constraints are solved: Gauss-Seidel sweeps of the XPBD projections
// (cheap, converges slowly on a stiff slender rod), or the XPBD system for every constraint at
// once by a linear solve along the chain per iteration (Deul et al. 2018; block_tridiagonal.h)
enum class RodSolver { kGaussSeidel, kDirect };

struct CosseratRodParams {
  double length_m = 0.30;                  // (0, 10]
  int segments = 50;                       // [1, 10000]
  double bending_stiffness_nm2 = 8e-5;     // E I, (0, inf)
  double torsional_stiffness_nm2 = 6e-5;   // G J, (0, inf)
  double axial_stiffness_n = 1.4e4;        // E A, (0, inf)
  double shear_stiffness_n = 4.9e3;        // kappa G A, (0, inf)
  double mass_per_length_kg_per_m = 7e-4;  // (0, inf)
  double outer_diameter_m = 0.356e-3;      // for the segments' rotational inertia, [0, inf)
  // rotary inertia scaling (as explicit beam codes do): the frames' inertia times this. A thin
  // rod's frames are so light next to its nodes that Gauss-Seidel hands most of each
  // stretch-shear correction to the frame, which the bend-twist constraint hands back: the
  // nodes hardly feel the bending stiffness and a bent rod stays bent (measured: the default
  // wire, bent at 10 x the step and unloaded, still bent after 20 s at scale 1; straight at 100). Static
  // answers do not depend on it; bending and twisting waves are slowed. [1, 1e9]
  double rotational_inertia_scale = 100.0;
  // the soft tip's nodes' mass times this for their motion (from the node where the tip begins;
  // their weight and their drag stay the rod's own: gravity's acceleration and damping_per_s on
  // them divided by it). A tip node pressed on a wall carries as much force as a body node with
  // as little mass; the substep's linearised answer must cover its motion under that force,
  // h^2 F / m, and at 1.2 mg it covered centimetres (issue #33, docs/guidewire.md). 10 x a
  // 12 mm tip's 9.5 mg puts its first bending mode at 27 Hz instead of 87; static answers do not
  // depend on it. [1, 1e6]
  double tip_mass_scale = 1.0;
  // velocity damping rate, linear (on each node's own mass: node_damping_per_s) and angular, [0, inf)
  double damping_per_s = 0.0;
  // defaults: the direct solve at 2 x 1 is within 0.05 % of the elastica at 50 segments and
  // 0.01 % at 100 (docs/benchmarks/rod.md); Gauss-Seidel needs about 40 x 10 for 0.1 % at 50
  RodSolver solver = RodSolver::kDirect;
  int substeps = 2;  // XPBD substeps per step, [1, 10000]
  // a step longer than substeps x this takes more substeps: at 10 x the 30 Hz step a single
  // direct solve per 1/6 s substep started from a prediction h^2 a metres away and did not
  // settle (the default wire under gravity and a tip load kept moving at 0.2-2 m/s). (0, inf)
  double max_substep_s = 1.0 / 60.0;
  int iterations = 1;  // per substep: Gauss-Seidel sweeps, or Newton iterations of the direct solve, [1, 10000]
  // after the sweeps, a segment longer or shorter than (1 +- stretch_guard) l is brought back
  // to that bound, from the clamp outwards (follow-the-leader, Mueller et al. 2012, "Fast
  // simulation of inextensible hair and fur"): a safeguard for unconverged sweeps, inactive
  // when they converge. 0 turns it off. [0, 1]
  double stretch_guard = 0.01;
  Eigen::Vector3d gravity_m_per_s2{0, 0, 0};  // finite
  // a softer distal tip: the last tip_length_m of the rod has its stiffnesses (EI, GJ) times
  // tip_stiffness_ratio (e.g. 1e-3 for a 1:1000 tip-to-body ratio). [0, length_m], (0, 1e6]
  double tip_length_m = 0.0;
  double tip_stiffness_ratio = 1.0;
};

// throws std::invalid_argument naming the first field out of range
void validate(const CosseratRodParams& params);

}  // namespace pcisim::physics::rod
