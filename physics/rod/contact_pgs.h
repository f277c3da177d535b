#pragma once
// The contact problem of a substep (issue #33): wall contact and Coulomb friction of k nodes,
// solved on the rod's contact compliance W = H A^-1 H^T (CosseratRod::contact_compliance) by
// projected Gauss-Seidel over the contacts, as SOFA's constraint solvers do for a beam (Duriez
// et al. 2006, "Realistic haptic rendering of interacting deformable objects in virtual
// environments": free motion, then this problem, then the correction). Per contact, with
// d = W L the nodes' motion under the impulses L (N s^2, force h^2, world frame):
//   non-penetration   gap + n.d <= 0,  L_n = -n.L >= 0,  L_n (gap + n.d) = 0
//   stick             slip + P d = 0 (P: the wall's tangent plane) while |L_t| <= mu_s L_n
//   slide             otherwise |L_t| = mu_k L_n, against the slip
//   curved wall       C = -L_n P S P (d - d_0): the normal turns by S (d - d_0) as the node moves
//                     along a wall of shape operator S linearised where the node moved d_0 (a
//                     push L_n along a turned normal: a tangent impulse that holds a node pressed
//                     into a rounded end or a tube's groove where the tangent plane lets it slide)
// Each sweep takes each contact's normal row (a scalar, clamped at 0), then its two tangent rows
// (a 2 x 2 solve, projected on the cone); the other nodes' motion follows once per contact.
// A frictionless contact on a curved wall takes its push and its curved wall's impulse together
// (Newton on the push: one after the other they chased each other where W couples the node's
// motion along the wall with its motion into it).
// (Accelerating the sweeps as a nonsmooth nonlinear conjugate gradient, Silcowitz et al. 2010,
// made a wire driven into a dead end blow up: tried 2026-11-28, not kept.)
// Every few sweeps a subspace step (after Silcowitz, Niebe & Erleben 2009, "Projected
// Gauss-Seidel subspace minimization for interactive rigid body dynamics"): the pushing contacts'
// gaps closed together by one solve on their rows of W, friction held, as far as no push turns
// into a pull; the sweeps go on from there. Neighbouring soft-tip nodes that barely touch hand a
// push back and forth for hundreds of sweeps (near-dependent rows of W); the solve settles them.
// Where the sweeps cycle (a window of kRelaxationWindow sweeps changes a contact as much as the
// window before) and any contact has friction, they are under-relaxed: each contact's impulses
// move half as far towards their update, halved again while they still cycle, down to a quarter.
// (Without friction, but for a curved wall's impulse, they minimise a convex quadratic: no
// cycling to cure.) A wire of negligible bending stiffness wrapped round a bend with mu 0.2
// cycled so: one of its 135-contact problems, dumped from pcisim-bench wire-force's capstan, still
// moved a contact 1e-5 m a sweep after 10 000 sweeps and converged in 402 under-relaxed (without
// the wire's 100-sweep cap; in the rig, capped, that row still misses: issue #33, session 31).
// Sized once; solve() allocates nothing.
#include <Eigen/Core>
#include <span>
#include <vector>

namespace pcisim::physics::rod {

struct NodeContact {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, out of the lumen: the wall pushes along -normal
  double gap_m = 0.0;                                 // after the free solve: > 0 is inside the wall
  Eigen::Vector3d slip_m = Eigen::Vector3d::Zero();   // the node's motion along the wall over the substep, free solve
  double mu_static = 0.0, mu_kinetic = 0.0;
  // the wall's shape operator (the normal's turn per metre along the wall, symmetric, in the
  // tangent plane; zero: a plane) and the motion d_0 where the wall was linearised
  Eigen::Matrix3d shape_per_m = Eigen::Matrix3d::Zero();
  Eigen::Vector3d linearised_at_m = Eigen::Vector3d::Zero();
};

struct ContactSolveStats {
  int sweeps = 0;
  int subspace_steps = 0;
  double last_change_m = 0.0;  // the largest motion any contact's update made in the last sweep
  bool converged = false;
  double relaxation = 1.0;  // the sweeps' relaxation at the end (below 1: they had cycled)
};

class ContactPgs {
 public:
  explicit ContactPgs(int max_contacts);
  int max_contacts() const { return static_cast<int>(motion_.size()); }
  // a subspace step after every this many sweeps (0: sweeps alone)
  void set_sweeps_per_subspace_step(int sweeps) { sweeps_per_subspace_ = sweeps; }
  // under-relax sweeps that cycle (on by default)
  void set_under_relaxation(bool on) { relax_ = on; }
  // impulses: one per contact, the warm start on entry and the answer on return (normal and
  // friction; the curved wall's impulse apart: curvature_impulses()). Sweeps until no
  // update moves its node more than tolerance_m, at most max_sweeps. w is 3k x 3k, k <= max_contacts.
  ContactSolveStats solve(const Eigen::Ref<const Eigen::MatrixXd>& w, std::span<const NodeContact> contacts,
                          std::span<Eigen::Vector3d> impulses, int max_sweeps, double tolerance_m);
  // the nodes' motion W L under the last answer
  std::span<const Eigen::Vector3d> motion_m() const { return motion_; }
  // each contact's curved-wall impulse C under the last answer (world frame, in its tangent plane)
  std::span<const Eigen::Vector3d> curvature_impulses() const { return curvature_; }

 private:
  // the subspace step; whether it changed the impulses
  bool subspace_step(const Eigen::Ref<const Eigen::MatrixXd>& w, std::span<const NodeContact> c,
                     std::span<Eigen::Vector3d> impulses);

  std::vector<Eigen::Vector3d> motion_, curvature_;
  std::vector<int> pushing_;            // the subspace step's contacts
  Eigen::MatrixXd subspace_;            // N' W N over them (its lower half)
  Eigen::VectorXd subspace_rhs_, sum_;  // the step's right side, then its answer; L + C back to back
  int sweeps_per_subspace_ = 8;
  bool relax_ = true;
};

}  // namespace pcisim::physics::rod
