#pragma once
// The guidewire as a discrete Cosserat rod (scene key guidewire.model = "rod"; issue #15): the
// rod of physics/rod/ with the wire's physical section, fed and turned through the guide
// catheter, touching the lumen wall with Coulomb friction.
//
// Node 0 is proximal, node N the tip. As in the chain-mail, a node whose arc length from the tip
// exceeds the fed length is inside the catheter: placed on the catheter path (kinematic), its
// segment's frame the catheter's turned by the hub rotation. The last such node is the rod's hub
// (CosseratRod::set_hub_node): the free rod is pushed, pulled and twisted through it, so feed
// reaches the tip through the rod's own axial stiffness and twist through its torsional stiffness
// (a lag, and a whip when friction lets go).
//
// Contact (after every solve of a substep): a free node closer than wall_margin_m to the wall
// (or outside) is moved back along the wall normal (the condition of [guidewire eq 15]); then
// Coulomb friction, decided on forces (the rod's constraint force along the wall against mu_s
// times the wall's) and applied to the node's motion over the substep, and the same about the
// wire's axis for the touching segments' spin (rod_wire.cc). The tip has its own coefficients,
// as in the chain-mail. The wall's normal force on a node is its mass times the correction over h^2.
//
// With guidewire.rod_contact "solve" (issue #33) the wall is part of the solve instead: after the
// rod's free solve, the nodes near the wall become contacts, their contact problem (non-
// penetration and Coulomb friction) is solved on the rod's contact compliance W = H A^-1 H^T
// (CosseratRod::contact_compliance, rod::ContactPgs) and the rod answers the impulses through its
// own stiffness, so the hub's force includes the wall's reaction. What the linearisation leaves
// inside a curved wall is moved out without velocity and reported (contact_report). The contact
// problem is linearised where the nodes stand after the free solve: where that stops being a
// small step (a node near the wall moved far in the substep, the wall's normal turned under it,
// or the answer leaves a node deep inside), the substep is taken back and tried at half the
// length, up to rod_substep_halvings times; a few good short substeps later the length doubles
// again (step()).
//
// With rod_contact kImplicit (issue #33; rigs only, no scene key) the wall is a stiff one-sided spring inside
// the rod's own solve (CosseratRod::set_node_spring, backward Euler): a node inside the wall
// margin is pulled back along the wall's normal by rod_wall_stiffness_n_per_m times its depth,
// and friction holds it by a tangential spring to where it stuck (the same stiffness) as long as
// that spring's force is within mu_s N, else drags it with mu_k N against its slip (the spring's
// stiffness mu_k N / slip, found again each round: a Coulomb law solved as a sequence of linear
// ones). The springs are placed again where the nodes end (the wall's normal and depth there)
// and the substep solved again, up to rod_contact_rounds times. Everything the wall does is a
// force inside the solve, so the rod's multipliers (the hub's force) carry it.
//
// Built once; step() allocates nothing.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "physics/guidewire/catheter_path.h"
#include "physics/guidewire/guidewire_params.h"
#include "physics/guidewire/lumen_query.h"
#include "physics/guidewire/wire_feedback.h"
#include "physics/rod/contact_pgs.h"
#include "physics/rod/cosserat_rod.h"

namespace pcisim::physics {

// the contact problem of the solve scheme over the last step
struct RodContactReport {
  int contacts = 0;         // in the last substep
  int most_contacts = 0;    // the most in any substep of the step
  int dropped = 0;          // candidates over the cap (kMaxRodContacts) in the step, the shallowest
  int most_sweeps = 0;      // the contact solve's sweeps, the most in a substep (implicit: its solves)
  int unconverged = 0;      // substeps whose solve stopped at the sweep cap
  double residual_m = 0.0;  // the deepest a node was left inside the wall after the solve (then moved out;
                            // implicit: the deepest into the margin its spring holds a node)
  int substeps = 0;         // substeps taken in the step (more than rod_substeps where some were halved)
  int retried = 0;          // substeps taken back and tried again at half the length
  int finest_halvings = 0;  // the shortest substep of the step: rod_substeps' halved this many times
};

// the most contacts one substep solves (the deepest are kept). A wire wrapped once round a 15 mm
// bend at 1 mm segments has 126-140 candidates; at 96 some 40 a substep were dropped
inline constexpr int kMaxRodContacts = 192;

class RodWire final : public rod::RodContact {
 public:
  // lumen, contact and friction may be null (no wall, no friction); the lumen must outlive the
  // wire. Throws std::invalid_argument on bad params.
  RodWire(const GuidewireParams& params, CatheterPath path, const LumenQuery* lumen = nullptr,
          std::optional<VesselContactParams> contact = std::nullopt,
          std::optional<FrictionParams> friction = std::nullopt);

  // the vessels move (guidewire.beat_coupling "contact"): the lumen and the catheter path are
  // described at rest, and `motion` says how far the wall stands off that frame through each
  // step. The wire then lives in the world: each node's rest point is found from its position
  // (x = r + d(r)), the lumen is sampled at x - d, friction acts on motion relative to the wall,
  // and the nodes in the catheter ride it. Null (the default): the wall stands still at rest.
  // `motion` must outlive the wire.
  void set_lumen_motion(const LumenMotion* motion);
  // each node's offset off the rest frame now (zero without a motion)
  std::span<const Eigen::Vector3d> wall_offset_m() const { return offset_; }

  // one physics step: feed to insertion_m (clamped to [0, length]; refused while the wire pushes
  // back harder than feed_refuse_force_n), hub turned to rotation_rad, then the rod's substeps
  void step(double insertion_m, double rotation_rad, double dt_s);

  int node_count() const { return rod_.node_count(); }
  int segment_count() const { return rod_.segment_count(); }
  int first_free_node() const { return rod_.hub_node() + 1; }
  std::span<const Eigen::Vector3d> nodes_m() const { return rod_.nodes_m(); }
  // free nodes may be moved between steps (blood drift, [guidewire eq 12])
  std::span<Eigen::Vector3d> mutable_nodes_m() { return rod_.mutable_nodes_m(); }
  bool node_in_tip(int i) const;
  std::span<const uint8_t> touched() const { return touched_; }  // per node, at the wall in the last step
  std::span<const uint8_t> stuck() const { return stuck_; }      // held by static friction in the last substep
  // the wall's normal force on each node over the last step, N
  std::span<const double> wall_force_n() const { return wall_force_n_; }
  double tip_contact_force_n() const;  // over the tip's nodes
  double commanded_feed_m() const { return commanded_feed_m_; }
  // feed held back because the wire pushes back or has nowhere to go (the hand feels it); a feed
  // faster than the rod is handed (120 mm/s) lags without being refused
  double refused_feed_m() const;
  double fed_length_m() const { return fed_m_; }
  double rotation_rad() const { return rotation_rad_; }
  // the axial force the wire pushes back on the hub with (positive resists insertion) and the
  // torque it turns back with (positive resists positive rotation), from the rod's multipliers
  double hub_axial_force_n() const { return hub_axial_n_; }
  double hub_torque_nm() const { return hub_torque_nm_; }
  // the axial push-back averaged over the last step's substeps (hub_axial_force_n is its last
  // substep's: where the substeps alternate, the two differ)
  double mean_hub_axial_force_n() const { return mean_hub_axial_n_; }
  // how much shorter the free wire is than its rest length (a dead end crumples it), m
  double compression_m() const { return compression_m_; }
  // the tip segment's material frame turned about the wire, against the hub's turn: radians of
  // twist the tip lags behind the hub (its bend direction measured in the catheter's frame)
  double tip_roll_rad() const;
  // eq 19's inputs for the local force model, from the rod's forces
  WireFeedback feedback() const;
  const rod::CosseratRod& rod() const { return rod_; }
  // loads for rigs and benches (the scenes use none): a dead force on a node, and gravity
  void set_node_force_n(int node, const Eigen::Vector3d& force_n) { rod_.set_node_force_n(node, force_n); }
  void set_gravity_m_per_s2(const Eigen::Vector3d& g) { rod_.set_gravity_m_per_s2(g); }
  const CatheterPath& path() const { return path_; }
  int64_t recoveries() const { return recoveries_; }
  const RodContactReport& contact_report() const { return report_; }
  // the wall's force on each node over the last step, world frame (the solve scheme's with its
  // friction; the projection's along the wall's inward normal, magnitude wall_force_n)
  std::span<const Eigen::Vector3d> wall_force_vector_n() const { return wall_force_vector_n_; }

  // RodContact: wall contact and friction of the free nodes
  void project(rod::CosseratRod& rod, int iteration, double substep_s) override;
  void after_substep(rod::CosseratRod& rod, double substep_s) override;
  bool uses_springs() const override { return params_.rod_contact == RodContactScheme::kImplicit; }
  bool place_springs(rod::CosseratRod& rod, int round, double substep_s) override;

 private:
  void place_in_catheter(double previous_fed_m, double dt_s);
  Eigen::Quaterniond catheter_frame(const Eigen::Vector3d& tangent) const;
  void recover();
  void find_rest_point(int i, double a, double dt_s);
  // the solve scheme's contact after the rod's last solve of a substep; sets retry_ instead
  // where the substep should be taken back and tried shorter
  void solve_contact(rod::CosseratRod& rod, double h);
  // the lumen's shape operator (1/m) at p (the lumen's frame) whose wall normal is n: dn/dx in
  // the tangent plane, its concave part
  Eigen::Matrix3d wall_shape(const Eigen::Vector3d& p, const Eigen::Vector3d& n) const;
  // contact a (node i) posed on the wall s sampled where the node stands (at_m) after moving d_m
  // in the problem's terms (from where it would be without the last substep's force), its motion
  // along the wall over the substep so far `moved_m`
  void pose_contact(int a, int i, const WallSample& s, const Eigen::Vector3d& at_m, const Eigen::Vector3d& d_m,
                    const Eigen::Vector3d& moved_m, double mu);
  // the spin about the wire's axis of touching segments held by static friction (every scheme)
  void hold_spin(rod::CosseratRod& rod);
  // the implicit scheme's friction anchors after an accepted substep
  void commit_anchors(rod::CosseratRod& rod, double h);
  double mu_static(int node) const;
  double mu_kinetic(int node) const;

  GuidewireParams params_;
  CatheterPath path_;
  const LumenQuery* lumen_;
  std::optional<VesselContactParams> contact_;
  std::optional<FrictionParams> friction_;
  rod::CosseratRod rod_;
  Eigen::Quaterniond exit_frame_;  // e3 along the exit, fixed in the world
  int tip_first_node_ = 0;
  std::vector<uint8_t> touched_, stuck_;
  // the solve scheme: static friction held the node in the last accepted substep, so its cone in
  // the next contact problem is the static one (else the kinetic one)
  std::vector<uint8_t> held_, saved_held_;
  std::vector<double> wall_impulse_n_s_, wall_force_n_;
  std::vector<double> substep_dn_m_;     // normal corrections so far in this substep
  std::vector<uint8_t> segment_stuck_;   // held about its axis by static friction this substep
  std::vector<double> node_wall_n_;      // the wall's force on each node in this substep
  std::vector<Eigen::Vector3d> normal_;  // the wall normal at the last contact
  // the moving wall (motion_): per node, its rest point, the wall's offset there at the step's
  // start and end and now (per substep), and the wall's motion per substep and velocity over the step
  const LumenMotion* motion_ = nullptr;
  std::vector<Eigen::Vector3d> rest_point_m_;
  std::vector<Eigen::Vector3d> offset_from_, offset_to_, offset_, wall_velocity_;
  double commanded_feed_m_ = 0.0, fed_m_ = 0.0, rotation_rad_ = 0.0;
  double rotation_before_step_rad_ = 0.0;
  double hub_axial_n_ = 0.0, hub_torque_nm_ = 0.0, mean_hub_axial_n_ = 0.0;
  double compression_m_ = 0.0;            // free wire shorter than its rest length, at the last step's end
  bool refusing_ = false;                 // feed held back this step
  bool tip_held_ = false;                 // the tip segment held about its axis by static friction
  double axial_stiffness_n_per_m_ = 0.0;  // measured between steps, for the local force model
  int64_t recoveries_ = 0;
  // the solve scheme: candidates, the chosen contacts, their problem and answer, and each node's
  // impulse of the last substep (the next one's warm start)
  rod::ContactPgs pgs_{0};
  Eigen::MatrixXd compliance_;
  // the solve scheme's curved-wall impulse per node this substep, and the answer with it (the
  // next substep's prediction takes it as the rod's contact force)
  std::vector<Eigen::Vector3d> curvature_impulse_, warm_total_, saved_warm_total_;
  std::vector<int> candidates_, contact_nodes_;
  std::vector<double> candidate_gap_m_;
  std::vector<WallSample> candidate_wall_;
  std::vector<rod::NodeContact> contacts_;
  std::vector<Eigen::Vector3d> contact_warm_motion_m_, contact_moved_m_;  // per contact, for re-posing
  std::vector<Eigen::Vector3d> contact_impulse_, node_impulse_, wall_impulse_vector_n_s_, wall_force_vector_n_;
  RodContactReport report_;
  // halved substeps (the solve scheme): the state before the substep being tried, whether the
  // contact asked for it to be taken back, how many times the substep is halved now, the good
  // substeps in a row at that length, and the last substep's length (the warm impulses scale with
  // its square)
  rod::RodState saved_rod_;
  std::vector<Eigen::Vector3d> saved_impulse_;
  std::vector<uint8_t> saved_touched_;
  RodContactReport saved_report_;
  bool retry_ = false;
  double substep_hub_axial_n_ = 0.0;  // the rod's push-back on the hub after the last accepted substep
  int halvings_ = 0, good_in_a_row_ = 0;
  double last_substep_s_ = 0.0;
  // the implicit scheme: per node, where its springs were last placed, their normal and whether
  // friction held it, the force of the springs the last solve ran with, and the point friction
  // holds it to (rest frame; anchored_ while it touches)
  std::vector<Eigen::Vector3d> spring_at_m_, spring_normal_, spring_force_n_, anchor_rest_m_;
  std::vector<uint8_t> spring_stuck_, anchored_;
  bool fell_back_ = false;                     // this substep's direct solve failed: the projection finished it
  std::vector<Eigen::Vector3d> saved_anchor_;  // (the halved substeps' copies)
  std::vector<uint8_t> saved_anchored_;
};

// the rod's section as CosseratRodParams (stiffness, mass, tip, substeps), documented in
// docs/guidewire.md
rod::CosseratRodParams rod_params_of(const GuidewireParams& params);

}  // namespace pcisim::physics
