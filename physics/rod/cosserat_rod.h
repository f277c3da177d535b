#pragma once
// A discrete Cosserat rod solved by XPBD (Kugelstadt & Schoemer 2016, "Position and orientation
// based Cosserat rods"; Macklin et al. 2016, XPBD): positions at N + 1 nodes, one unit
// quaternion per segment (its material frame; the third director is the tangent), a
// stretch-shear constraint per segment and a bend-twist constraint per pair of neighbouring
// segments (cosserat_constraints.h). Node 0 is clamped at the hub: its position and a clamp
// frame are prescribed. The clamp frame is tied to segment 0 by a bend-twist constraint over
// half a segment (the clamp sits at s = 0, segment 0's frame at s = l / 2): fixing segment 0's
// own orientation instead would move the clamp to l / 2 and shorten the free rod by half a
// segment, a first-order error (about 1.5 / N in the cantilever's tip deflection).
//
// Inertia: lumped node masses (mu l inside, mu l / 2 at the tip) and, as in the paper, one
// scalar rotational inertia per segment, I = mu l (l^2 / 12 + r^2 / 4) (a bar about an axis
// across it; the axial moment of a thin wire, mu l r^2 / 2, is far smaller and is not used).
//
// The hub: nodes [0, hub] and the segments between them follow the instrument (inside a guide
// catheter, set by the caller); the rod is solved from segment `hub` on. hub = 0 is the clamp
// above. A contact hook (RodContact) runs after each solve inside the substeps.
//
// Everything is allocated at construction; step() allocates nothing.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <span>
#include <vector>

#include "physics/rod/block_tridiagonal.h"
#include "physics/rod/cosserat_rod_params.h"

namespace pcisim::physics::rod {

class CosseratRod;

// what the rod asks of its surroundings after each solve of a substep (iteration 0, 1, ...):
// move the free nodes (from hub_node() + 1 on) out of whatever they touch, and hold or slow them
class RodContact {
 public:
  virtual ~RodContact() = default;
  virtual void project(CosseratRod& rod, int iteration, double substep_s) = 0;
  // after the substep's velocities are known (e.g. kinetic friction on them)
  virtual void after_substep(CosseratRod& /*rod*/, double /*substep_s*/) {}
  // springs instead of project() (direct solver only): place_springs is called after the
  // prediction (round 0) and after each solve of the substep (round 1, 2, ...) with the nodes
  // where they stand; it sets or clears the nodes' springs (set_node_spring) and returns true to
  // solve the substep again from its prediction with them (round 0's answer is not read; round 0
  // may move nodes with shift_node_without_velocity, which the rounds then start from)
  virtual bool uses_springs() const { return false; }
  virtual bool place_springs(CosseratRod& /*rod*/, int /*round*/, double /*substep_s*/) { return false; }
};

// what a substep changes of the rod (positions, frames, velocities, the hub and its clamp), so a
// caller can take a substep back and try it shorter (RodWire's halved substeps, issue #33).
// Sized by the first save_state; later saves into the same RodState allocate nothing
struct RodState {
  std::vector<Eigen::Vector3d> x, v, omega;
  std::vector<Eigen::Quaterniond> q;
  Eigen::Quaterniond clamp_q = Eigen::Quaterniond::Identity();
  int hub = 0;
};

class CosseratRod {
 public:
  // a straight rod at rest from clamp_position_m along clamp_orientation's third director (e3);
  // throws std::invalid_argument on bad params
  explicit CosseratRod(const CosseratRodParams& params,
                       const Eigen::Vector3d& clamp_position_m = Eigen::Vector3d::Zero(),
                       const Eigen::Quaterniond& clamp_orientation = Eigen::Quaterniond::Identity());

  // advances dt_s: params.substeps XPBD substeps (more when dt_s / substeps > max_substep_s) of
  // params.iterations solves, each followed by contact->project when given
  void step(double dt_s, RodContact* contact = nullptr);

  // a dead force on a node (kept until changed); node 0 is clamped and ignores it
  void set_node_force_n(int node, const Eigen::Vector3d& force_n);
  void clear_node_forces();
  // a contact hook's force on a node for the next substeps' prediction, beside the dead force
  // above (RodWire's wall: the last substep's answer, so the solve starts where the wall held
  // the rod); node 0 and the hub's nodes ignore it
  void set_node_contact_force_n(int node, const Eigen::Vector3d& force_n);
  void set_gravity_m_per_s2(const Eigen::Vector3d& gravity) { params_.gravity_m_per_s2 = gravity; }
  // moves the hub: the clamped node and the clamp frame (insertion and rotation)
  void set_clamp(const Eigen::Vector3d& position_m, const Eigen::Quaterniond& orientation);
  // nodes [0, hub_node] and segments [0, hub_node) become kinematic: the caller places them
  // (mutable_nodes_m, mutable_orientations) before each step; the others are free. [0, segments)
  void set_hub_node(int hub_node);
  int hub_node() const { return hub_; }
  // the rest curvature and twist of a pair (e.g. a shaped tip), per metre, in its first frame
  void set_rest_darboux_per_m(int pair, const Eigen::Vector3d& darboux_per_m);
  // what the free rod does to the hub over the last substep (direct solver: from the multipliers
  // of segment `hub`'s constraints, f = J^T lambda / h^2; zero when Gauss-Seidel solved it):
  // the force on the hub node and the torque on the hub's frame, world frame
  Eigen::Vector3d hub_force_n() const;
  Eigen::Vector3d hub_torque_nm() const;
  // inside a substep, after a direct solve (zero for Gauss-Seidel): the constraints' force on a
  // free node and their torque on a free segment's frame, J^T lambda / h^2, world frame
  Eigen::Vector3d node_constraint_force_n(int node) const;
  Eigen::Vector3d segment_constraint_torque_nm(int segment) const;
  // --- wall contact inside the solve (issue #33): for a RodContact hook after a direct solve ---
  // the contact compliance (Delassus operator) W = H A^-1 H^T of free nodes: how far each listed
  // node moves (m, world frame) per unit impulse (N s^2, force h^2) on any listed node, through
  // this substep's linearised rod: A^-1 = (M + J^T alpha~^-1 J)^-1 = W_z - W_z J^T S^-1 J W_z
  // (Woodbury), with S the system the solve just factored. `nodes` are free (> hub_node()),
  // strictly increasing, k of them; w is 3k x 3k, row/column 3a + d for node a, axis d.
  // False (w untouched) when the last solve was not direct or the arguments do not fit.
  bool contact_compliance(std::span<const int> nodes, Eigen::Ref<Eigen::MatrixXd> w);
  // the rod's response to impulses on the listed nodes (same rules): the multipliers change by
  // dl = -S^-1 J W_z H^T L (so the hub's force includes the wall's reaction) and the nodes and
  // frames move by W_z (J^T dl + H^T L)
  bool apply_contact_impulses(std::span<const int> nodes, std::span<const Eigen::Vector3d> impulses_n_s2);
  // --- implicit springs on free nodes (a RodContact that uses_springs; issue #33) ---
  // force -K (x - anchor) on the node through the substep's solve, taken implicitly with the
  // rod (backward Euler): the node's mass matrix becomes M + h^2 K and its prediction moves
  // towards the anchor, x^ = (M + h^2 K)^-1 (M x~ + h^2 K anchor). K symmetric positive
  // semidefinite, N/m. Kept until cleared; ignored on kinematic nodes
  void set_node_spring(int node, const Eigen::Matrix3d& k_n_per_m, const Eigen::Vector3d& anchor_m);
  void clear_node_spring(int node);
  bool has_node_spring(int node) const { return spring_on_[node] != 0; }
  // the spring's force on the node where it stands now (zero without one)
  Eigen::Vector3d node_spring_force_n(int node) const;
  // moves a free node, and where its substep began, by d: a position fix that makes no velocity
  void shift_node_without_velocity(int node, const Eigen::Vector3d& d_m);
  // where the nodes and frames were when the current substep began
  std::span<const Eigen::Vector3d> substep_start_nodes_m() const { return x_old_; }
  std::span<const Eigen::Quaterniond> substep_start_orientations() const { return q_old_; }
  // the scalar rotational inertia of a segment's frame (params' scaling included)
  double segment_inertia_kg_m2(int segment) const { return 0.25 / inv_inertia_q_[segment]; }
  int segment_count() const { return n_; }
  int node_count() const { return n_ + 1; }
  double segment_length_m() const { return l_; }
  const CosseratRodParams& params() const { return params_; }
  std::span<const Eigen::Vector3d> nodes_m() const { return x_; }
  std::span<Eigen::Vector3d> mutable_nodes_m() { return x_; }
  std::span<const Eigen::Quaterniond> orientations() const { return q_; }
  std::span<Eigen::Quaterniond> mutable_orientations() { return q_; }
  std::span<const Eigen::Vector3d> velocities_m_per_s() const { return v_; }
  std::span<Eigen::Vector3d> mutable_velocities_m_per_s() { return v_; }
  // each segment's angular velocity in its material frame (z: spin about the wire)
  std::span<Eigen::Vector3d> mutable_angular_velocities_rad_per_s() { return omega_; }
  const Eigen::Quaterniond& clamp_orientation() const { return clamp_q_; }
  const Eigen::Vector3d& node_force_n(int node) const { return force_[node]; }
  // the node's mass as its motion sees it (params' tip_mass_scale included), and its own (its weight's)
  double node_mass_kg(int node) const { return mass_[node]; }
  double node_own_mass_kg(int node) const { return own_mass_share_[node] * mass_[node]; }
  // the node's drag rate: damping_per_s on its own mass (a node heavier for its motion takes its
  // share), the rate its velocity relaxes at
  double node_damping_per_s(int node) const { return own_mass_share_[node] * params_.damping_per_s; }
  // stiffness per material component: stretch-shear (GA, GA, EA) of a segment, bend-twist
  // (EI, EI, GJ) of a pair. Pair 0 joins the clamp frame and segment 0, pair j segments j-1, j.
  const Eigen::Vector3d& stretch_shear_stiffness(int segment) const { return ss_stiffness_[segment]; }
  const Eigen::Vector3d& bend_twist_stiffness(int pair) const { return bt_stiffness_[pair]; }
  // the length a pair's bend and twist are spread over: half a segment at the clamp (pair 0) and
  // at the hub (the wire is straight inside the catheter up to the hub node, so the bend
  // between the last kinematic frame and the first free one happens over the free half only), a
  // segment elsewhere
  double dual_length_m(int pair) const { return pair == 0 || pair == hub_ ? 0.5 * l_ : l_; }
  const Eigen::Vector3d& rest_darboux_per_m(int pair) const { return rest_darboux_[pair]; }
  // the frame before pair j's second segment: the clamp frame for pair 0
  const Eigen::Quaterniond& pair_first_frame(int pair) const { return pair == 0 ? clamp_q_ : q_[pair - 1]; }
  // the state a substep changes, and back to it (the multipliers and forces of the last substep
  // are not restored: the next substep computes them again); restore_state throws
  // std::invalid_argument for a state of another size
  void save_state(RodState& s) const;
  void restore_state(const RodState& s);
  // largest node speed, for "came to rest" checks
  double max_speed_m_per_s() const;
  bool all_finite() const;

 private:
  void predict(double h);
  void solve_constraints(double h, RodContact* contact);
  // returns false (and leaves the state as the last good iteration) when the system is singular
  bool solve_constraints_direct(double h, RodContact* contact);
  bool direct_iteration(double h);
  // the substep with a spring hook: rounds of the direct solve (params.iterations each) from the
  // prediction, the hook placing the springs before each (RodContact::place_springs); false as
  // the direct solve
  bool solve_with_springs(double h, RodContact* contact);
  // the inverse mass of a node as the solve sees it: 1 / m, or (M + h^2 K)^-1 with a spring
  Eigen::Matrix3d node_inverse_mass(int i) const;
  // after a direct solve of dlambda_: lambda += dlambda, x += W_z J^T dlambda, frames likewise
  void apply_multiplier_change();
  bool contact_nodes_fit(std::span<const int> nodes) const;
  void guard_stretch();
  void update_velocities(double h);

  CosseratRodParams params_;
  int n_;
  double l_;
  std::vector<Eigen::Vector3d> x_, x_old_, v_, force_, contact_force_;
  std::vector<double> mass_, inv_mass_;
  std::vector<double> own_mass_share_;  // own mass over the mass the motion sees (tip_mass_scale)
  std::vector<Eigen::Quaterniond> q_, q_old_;
  std::vector<Eigen::Vector3d> omega_;  // angular velocity per segment, material frame
  std::vector<double> inv_inertia_q_;   // inverse "mass" of the quaternion as a 4-vector, 1 / (4 I)
  std::vector<Eigen::Vector3d> ss_stiffness_, ss_compliance_, ss_lambda_;
  // bt_compliance_ per metre of the pair's dual length (1 / stiffness): divided by it where used
  std::vector<Eigen::Vector3d> bt_stiffness_, bt_compliance_, bt_lambda_, rest_darboux_;
  Eigen::Quaterniond clamp_q_;
  int hub_ = 0;
  double last_h_ = 0.0;      // the last substep, for the hub's force
  bool direct_ran_ = false;  // the last substep was solved directly (its multipliers are world-frame)
  // the direct solve's system and per-iteration buffers (one 6-unit per segment: stretch-shear
  // in the world frame, then bend-twist of the pair ending at that segment)
  BlockTridiagonal6 system_;
  std::vector<BlockTridiagonal6::Vector> rhs_, dlambda_;
  std::vector<BlockTridiagonal6::Columns3> column_rhs_, column_;  // contact_compliance's columns
  std::vector<Eigen::Matrix3d> ss_jacobian_, bt_jacobian_;
  // the springs, and the substep's prediction the rounds start from
  std::vector<uint8_t> spring_on_;
  std::vector<Eigen::Matrix3d> spring_k_, spring_w_;
  std::vector<Eigen::Vector3d> spring_anchor_, x_pred_;
  std::vector<Eigen::Quaterniond> q_pred_;
  bool springs_in_solve_ = false;  // inside solve_with_springs: the solve reads the springs
};

}  // namespace pcisim::physics::rod
