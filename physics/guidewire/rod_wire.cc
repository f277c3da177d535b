#include "physics/guidewire/rod_wire.h"

#include <algorithm>
#include <cmath>
#include <Eigen/Eigenvalues>
#include <numbers>

#include "physics/guidewire/link_spec.h"
#include "physics/guidewire/rest_point.h"

namespace pcisim::physics {
namespace {

// the fastest feed the rod is handed: a larger jump of the instrument is taken over the next
// steps (not refused: the hand feels nothing for it), so nodes leave the catheter a few at a
// time and meet the wall
constexpr double kMaxFeedSpeedMPerS = 0.12;
// the moving wall: how far a node may move through its vessel within a step before its rest
// point is found again (rest_point.h; the offset is a node's own: the vessels' motion differs by
// millimetres across the LM's ostium, where the aortic root stands still)
constexpr double kRestPointRefreshM = 0.5e-3;
// the longest substep (a longer physics step takes more substeps, as the rod itself does)
constexpr double kMaxSubstepS = 1.0 / 60.0;
// the free wire may be this much shorter than its length before the hub refuses feed: the wall
// projection ends each substep, so a wire pressed against a wall crumples where it presses
// (measured on the trainee script down the LAD: up to 10 mm, released when the tip slips on);
// one driven into a dead end keeps crumpling, and this bound makes the hub slip instead
constexpr double kMaxCompressionM = 0.02;
// the solve scheme: a node becomes a contact when the free solve leaves it within this of the
// wall (a node further in is not reached by the correction of one substep, and one the
// correction does push in is moved out afterwards and reported); the contact solve's sweeps stop
// once no update moves a node more than the tolerance, or at the cap; a node whose motion along
// the wall is below kStuckM over a substep counts as held by static friction
constexpr double kContactBandM = 0.1e-3;
// an answer that leaves a node where its wall's normal may have turned by more than
// kReposeTurnRad from where the wall was linearised (|d - d_0| |S|, S's Frobenius norm: a bound,
// sqrt 2 over the turn in a rounded end, where 0.02 rad is 0.008 mm at 0.55 mm radius, and
// counting motion along the normal and along a tube's axis too; S keeps only the wall's concave
// part, so on a convex wall only the distance counts), or more than kReposeM from there (another
// wall may be nearer), is posed again there, up to kReposeRounds times a substep. (The turn
// itself, |S (d - d_0)|, was tried: the end-on test's column then folded back 23 mm, as it did
// posing again beyond 0.02 mm whatever the turn; this bound kept it within 2.6 mm: the column
// after its buckle is chaotic, issue #33)
constexpr double kReposeTurnRad = 0.02;
constexpr double kReposeM = 0.25e-3;
constexpr int kReposeRounds = 3;
constexpr int kContactSweeps = 100;
// the sweeps stop once no update moves a node more than the tolerance; what is left unresolved
// is a speed over the substep: at 1e-7 m a wire resting round a bend with friction buzzed at
// 2.4e-5 m/s for ever (kinetic energy 1e-16-1e-13 J, the hub 0.008-0.020 N step to step); at
// 1e-10 m it rests (7.6e-23 J; RodWallSolve.AWireRoundABendRests...). Where the sweeps do not
// converge they now run to the cap: the capstan's rows 20-70 % slower a step
constexpr double kContactToleranceM = 1e-10;
constexpr double kStuckM = 1e-8;
// halved substeps (the solve scheme): a substep is taken back when a contact moved more than
// kRetryMotionM relative to its wall (a third of a coronary lumen's radius would cross it; only
// its motion towards or away from the wall was tried, 2026-11-28: 14 x fewer retries round the
// bend, but the wire fed at 40 mm/s into a dead end blew up), when
// the wall's normal turned by more than kRetryTurnDeg between where the node began and where it
// is (the tangent plane is no longer the wall it meets), or when the answer leaves a node more
// than kRetryResidualM inside (issue #33's penetration target); the length doubles again after
// kGoodSubstepsBeforeLonger good substeps in a row
constexpr double kRetryMotionM = 0.25e-3;
constexpr double kRetryTurnDeg = 20.0;
constexpr double kRetryResidualM = 0.05e-3;
// the solve scheme's soft-tip mass scale (CosseratRodParams::tip_mass_scale): the last substep's
// wall force is in each substep's prediction and taken back through W where a contact lets go; on
// a 1.2 mg soft-tip node pressed with 0.05-0.09 N that linear take-back moved it 15-589 mm at the
// shortest substep. Ten times heavier (measured 2026-11-30, three substep counts): the default
// scene's retried substeps 959-2 397 -> 544-624, the dead end 57 -> 7.7 ms a step p50, the
// torque lag with friction 7.1 -> 8.1 deg (all nodes ten times heavier moved it to 45 deg and
// the capstan -37 %)
constexpr double kSolveTipMassScale = 10.0;
// the wall's curvature in the contact problem: the normal sampled this far either side of a node
// along the wall
constexpr double kShapeStepM = 0.02e-3;
constexpr int kGoodSubstepsBeforeLonger = 4;
// the implicit scheme: the contacts have settled when no node moved more than this between two
// solves of a substep (at the default wall stiffness, 0.02 N of wall force); a node that begins a
// substep deeper in the wall than kSpringDeepM (issue #33's penetration bound; the spring holds
// 1 N at a fifth of it) is moved back to that depth without velocity (the spring would shoot it
// out at depth / h), and a substep whose last solve leaves a node without a spring deeper than
// that is taken back and halved
constexpr double kSpringSettledM = 0.2e-6;
constexpr double kSpringDeepM = 0.05e-3;

}  // namespace

rod::CosseratRodParams rod_params_of(const GuidewireParams& g) {
  rod::CosseratRodParams p;
  p.length_m = g.length_m;
  p.segments = g.segment_count;
  p.bending_stiffness_nm2 = g.bending_stiffness_nm2;
  p.torsional_stiffness_nm2 = g.torsional_rigidity_nm2;
  // stiff enough that the wire neither stretches nor shears visibly; the direct solve does not
  // mind the ratio to the bending stiffness
  p.axial_stiffness_n = kWireAxialStiffnessN;
  p.shear_stiffness_n = kWireShearStiffnessN;
  p.mass_per_length_kg_per_m = g.mass_per_length_kg_per_m;
  p.outer_diameter_m = g.outer_diameter_m;
  p.damping_per_s = g.rod_damping_per_s;
  // the wall inside the solve: the soft tip's nodes kSolveTipMassScale heavier for their motion
  if (g.rod_contact == RodContactScheme::kSolve) p.tip_mass_scale = kSolveTipMassScale;
  p.solver = rod::RodSolver::kDirect;
  // the follow-the-leader guard is for unconverged Gauss-Seidel sweeps; after the direct solve
  // and the wall projection it only moved nodes back out of the wall
  p.stretch_guard = 0.0;
  // RodWire runs the substeps itself (the hub moves a little before each): one per rod step
  p.substeps = 1;
  p.max_substep_s = 1e9;
  p.iterations = g.rod_iterations;
  p.tip_length_m = g.tip_length_m;
  // the tip's bending and torsional stiffness scaled together (a ground core under a coil)
  p.tip_stiffness_ratio = g.tip_bending_stiffness_nm2 / g.bending_stiffness_nm2;
  return p;
}

RodWire::RodWire(const GuidewireParams& params, CatheterPath path, const LumenQuery* lumen,
                 std::optional<VesselContactParams> contact, std::optional<FrictionParams> friction)
    : params_((validate(params), params)),
      path_(std::move(path)),
      lumen_(lumen),
      contact_(contact),
      friction_(friction),
      rod_(rod_params_of(params), path_.exit_m(),
           Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), path_.exit_direction())),
      exit_frame_(Eigen::Quaterniond::Identity()) {
  if (contact_ && !lumen_) throw std::invalid_argument("guidewire: wall contact needs a lumen");
  // at rotation 0 the pre-bent tip bends the way the catheter curves, as the chain-mail's does:
  // the tip's rest curvature about d1 bends d3 towards -d2, so the exit frame is (t x b, -b, t)
  const Eigen::Vector3d t = path_.exit_direction();
  const Eigen::Vector3d b = path_.exit_curl();
  Eigen::Matrix3d frame;
  frame.col(0) = t.cross(b);
  frame.col(1) = -b;
  frame.col(2) = t;
  exit_frame_ = Eigen::Quaterniond(frame);
  const int n = rod_.segment_count();
  const double l = rod_.segment_length_m();
  // the shaped tip: its pre-bend spread evenly over the tip's pairs, a rest curvature about the
  // material d1 (the chain-mail spreads it over its tip links the same way)
  const double tip_start_m = params_.length_m - params_.tip_length_m;
  tip_first_node_ = n + 1;
  if (params_.tip_length_m > 0.0) {
    tip_first_node_ = std::min(n, static_cast<int>(std::ceil(tip_start_m / l - 1e-9)));
    int pairs = 0;
    for (int j = 1; j < n; ++j) pairs += j * l > tip_start_m + 1e-12 ? 1 : 0;
    // the whole angle over the pairs that carry it (as the chain-mail spreads it over its links)
    const double kappa = pairs > 0 ? params_.tip_angle_deg * std::numbers::pi / 180.0 / (pairs * l) : 0.0;
    for (int j = 1; j < n; ++j)
      if (j * l > tip_start_m + 1e-12) rod_.set_rest_darboux_per_m(j, Eigen::Vector3d(kappa, 0.0, 0.0));
  }
  touched_.assign(n + 1, 0);
  substep_dn_m_.assign(n + 1, 0.0);
  segment_stuck_.assign(n, 0);
  node_wall_n_.assign(n + 1, 0.0);
  normal_.assign(n + 1, Eigen::Vector3d::Zero());
  stuck_.assign(n + 1, 0);
  held_.assign(n + 1, 0);
  wall_impulse_n_s_.assign(n + 1, 0.0);
  wall_force_n_.assign(n + 1, 0.0);
  for (auto* v : {&rest_point_m_, &offset_from_, &offset_to_, &offset_, &wall_velocity_})
    v->assign(n + 1, Eigen::Vector3d::Zero());
  if (params_.rod_contact == RodContactScheme::kSolve) {
    pgs_ = rod::ContactPgs(kMaxRodContacts);
    compliance_.setZero(3 * kMaxRodContacts, 3 * kMaxRodContacts);
    curvature_impulse_.assign(n + 1, Eigen::Vector3d::Zero());
    warm_total_.assign(n + 1, Eigen::Vector3d::Zero());
    saved_warm_total_ = warm_total_;
    candidates_.assign(n + 1, 0);
    candidate_gap_m_.assign(n + 1, 0.0);
    candidate_wall_.assign(n + 1, WallSample{});
    contact_nodes_.reserve(kMaxRodContacts);
    contacts_.reserve(kMaxRodContacts);
    contact_impulse_.reserve(kMaxRodContacts);
    contact_warm_motion_m_.reserve(kMaxRodContacts);
    contact_moved_m_.reserve(kMaxRodContacts);
  }
  for (auto* v : {&spring_at_m_, &spring_normal_, &spring_force_n_, &anchor_rest_m_})
    v->assign(n + 1, Eigen::Vector3d::Zero());
  spring_stuck_.assign(n + 1, 0);
  anchored_.assign(n + 1, 0);
  node_impulse_.assign(n + 1, Eigen::Vector3d::Zero());
  wall_impulse_vector_n_s_.assign(n + 1, Eigen::Vector3d::Zero());
  wall_force_vector_n_.assign(n + 1, Eigen::Vector3d::Zero());
  // the halved substeps' copies, sized once
  rod_.save_state(saved_rod_);
  saved_impulse_ = node_impulse_;
  saved_touched_ = touched_;
  saved_held_ = held_;
  saved_anchor_ = anchor_rest_m_;
  saved_anchored_ = anchored_;
  // start fully inside the catheter, the tip at the exit
  place_in_catheter(0.0, 1.0);
  const auto x = rod_.mutable_nodes_m();
  const auto q = rod_.mutable_orientations();
  for (int j = rod_.hub_node(); j < n; ++j) q[j] = catheter_frame(path_.exit_direction());
  x[n] = path_.exit_m();
}

bool RodWire::node_in_tip(int i) const {
  return i >= tip_first_node_;
}

double RodWire::tip_contact_force_n() const {
  double f = 0.0;
  for (int i = std::max(tip_first_node_, first_free_node()); i < node_count(); ++i) f += wall_force_n_[i];
  return f;
}

// the catheter's material frame bent onto `tangent`, turned by the hub's rotation about the wire
Eigen::Quaterniond RodWire::catheter_frame(const Eigen::Vector3d& tangent) const {
  return Eigen::Quaterniond::FromTwoVectors(path_.exit_direction(), tangent) * exit_frame_ *
         Eigen::Quaterniond(Eigen::AngleAxisd(rotation_rad_, Eigen::Vector3d::UnitZ()));
}

// nodes still inside the catheter sit on its path; nodes the feed took out this step continue
// straight out of the exit; the last node inside is the rod's hub
void RodWire::place_in_catheter(double previous_fed_m, double dt_s) {
  const int n = rod_.segment_count();
  const double l = rod_.segment_length_m(), length = params_.length_m;
  const int old_hub = rod_.hub_node();
  const int hub = std::clamp(static_cast<int>(std::floor((length - fed_m_) / l + 1e-9)), 0, n - 1);
  const auto x = rod_.mutable_nodes_m();
  const auto v = rod_.mutable_velocities_m_per_s();
  const auto q = rod_.mutable_orientations();
  const Eigen::Vector3d& exit = path_.exit_m();
  const Eigen::Vector3d& dir = path_.exit_direction();
  const Eigen::Vector3d feed_velocity = (fed_m_ - previous_fed_m) / dt_s * dir;
  for (int i = 0; i <= hub; ++i) x[i] = path_.point_behind_exit(std::max(length - i * l - fed_m_, 0.0)) + offset_[i];
  for (int i = hub + 1; i <= old_hub; ++i) {
    x[i] = exit + std::max(fed_m_ - (length - i * l), 0.0) * dir + offset_[i];
    v[i] = feed_velocity + wall_velocity_[i];
  }
  for (int j = 0; j < hub; ++j) {
    const Eigen::Vector3d d = x[j + 1] - x[j];
    q[j] = catheter_frame(d.norm() > 1e-12 ? Eigen::Vector3d(d.normalized()) : dir);
  }
  for (int j = hub; j < old_hub; ++j) q[j] = catheter_frame(dir);
  const Eigen::Vector3d d0 = hub > 0 ? Eigen::Vector3d(x[1] - x[0]) : dir;
  rod_.set_clamp(x[0], catheter_frame(d0.norm() > 1e-12 ? Eigen::Vector3d(d0.normalized()) : dir));
  rod_.set_hub_node(hub);
}

void RodWire::set_lumen_motion(const LumenMotion* motion) {
  motion_ = motion;
  if (motion_) return;
  // no motion: the wall stands at rest again (the nodes follow it through contact)
  for (auto* v : {&offset_from_, &offset_to_, &offset_, &wall_velocity_})
    std::fill(v->begin(), v->end(), Eigen::Vector3d::Zero());
}

// node i's rest point r (x = r + d(r, a): rest_point.h; a free node's checked against its
// neighbour's nearer the hub, found first) and the wall's offset there at the step's start and end
void RodWire::find_rest_point(int i, double a, double dt_s) {
  const Eigen::Vector3d& x = rod_.nodes_m()[i];
  const bool free = i > rod_.hub_node();
  const Eigen::Vector3d neighbour =
      free ? Eigen::Vector3d(offset_from_[i - 1] + a * (offset_to_[i - 1] - offset_from_[i - 1]))
           : Eigen::Vector3d::Zero();
  const Eigen::Vector3d r = wire_node_rest_point(*motion_, x, offset_[i], free ? &neighbour : nullptr, a);
  rest_point_m_[i] = r;
  offset_from_[i] = motion_->displacement_m(r, 0.0);
  offset_to_[i] = motion_->displacement_m(r, 1.0);
  if (!offset_from_[i].allFinite() || !offset_to_[i].allFinite())
    offset_from_[i] = offset_to_[i] = Eigen::Vector3d::Zero();
  wall_velocity_[i] = (offset_to_[i] - offset_from_[i]) / dt_s;
}

void RodWire::step(double insertion_m, double rotation_rad, double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return;
  if (std::isfinite(insertion_m)) commanded_feed_m_ = std::clamp(insertion_m, 0.0, params_.length_m);
  if (std::isfinite(rotation_rad)) rotation_rad_ = rotation_rad;  // the target; reached over the substeps
  const double previous_fed_m = fed_m_, previous_rotation_rad = rotation_before_step_rad_;
  double target = commanded_feed_m_;
  // the grip slips while the wire pushes back harder than it holds, or while the free wire is
  // shorter than what was fed (it has nowhere to go): no further feed, and what is held back is
  // refused (the hand feels it)
  refusing_ = target > fed_m_ && (hub_axial_n_ > params_.feed_refuse_force_n || compression_m_ > kMaxCompressionM);
  if (refusing_) target = fed_m_;
  const double cap_m = kMaxFeedSpeedMPerS * dt_s;
  const double fed_target_m = std::clamp(target, fed_m_ - cap_m, fed_m_ + cap_m);
  const double rotation_target_rad = rotation_rad_;

  std::fill(touched_.begin(), touched_.end(), 0);
  std::fill(stuck_.begin(), stuck_.end(), 0);
  std::fill(wall_impulse_n_s_.begin(), wall_impulse_n_s_.end(), 0.0);
  std::fill(wall_impulse_vector_n_s_.begin(), wall_impulse_vector_n_s_.end(), Eigen::Vector3d::Zero());
  report_ = RodContactReport{};
  // the hub moves to the new feed and turn in equal parts, one before each substep: a whole
  // step's feed handed to the first substep crumpled the wire against the first bend it met
  // (measured: 2 substeps, 90 mm fed in a curved tube, the tip stopped 35 mm short)
  const int substeps =
      std::max(params_.rod_substeps, static_cast<int>(std::min(std::ceil(dt_s / kMaxSubstepS - 1e-9), 10000.0)));
  // the step is counted in ticks of the shortest substep allowed; a substep of `halvings_` is
  // 2^(most - halvings_) ticks, so a halved substep and the later longer ones stay on one grid
  const int most = params_.rod_contact != RodContactScheme::kProjection ? params_.rod_substep_halvings : 0;
  halvings_ = std::min(halvings_, most);
  const int64_t ticks_per_substep = int64_t{1} << most, ticks = substeps * ticks_per_substep;
  // the moving wall: every node's rest point at the step's start
  if (motion_)
    for (int i = 0; i < node_count(); ++i) find_rest_point(i, 0.0, dt_s);
  bool feed_stopped = refusing_;
  double hub_impulse_n_s = 0.0;  // the hub's push-back over the accepted substeps
  for (int64_t done = 0; done < ticks;) {
    const int64_t span = ticks_per_substep >> halvings_;
    const double a0 = static_cast<double>(done) / ticks, a = static_cast<double>(done + span) / ticks;
    const double h = dt_s * static_cast<double>(span) / ticks;
    if (most > 0) {
      rod_.save_state(saved_rod_);
      saved_impulse_ = node_impulse_;
      saved_warm_total_ = warm_total_;
      saved_touched_ = touched_;
      saved_held_ = held_;
      saved_report_ = report_;
      saved_anchor_ = anchor_rest_m_;
      saved_anchored_ = anchored_;
    }
    const double before_m = fed_m_, rotation_before_rad = rotation_rad_;
    // with the wall inside the solve the hub's force is the wall's too, so the grip slips as soon
    // as it exceeds the limit, within the step: a whole step's feed pushed into a jammed wire
    // (4 mm at the fastest feed) is more than one substep's contact problem can answer
    const bool stop_feed = params_.rod_contact != RodContactScheme::kProjection && !feed_stopped &&
                           fed_target_m > fed_m_ && substep_hub_axial_n_ > params_.feed_refuse_force_n;
    if (!feed_stopped) fed_m_ = previous_fed_m + a * (fed_target_m - previous_fed_m);
    if (stop_feed) fed_m_ = before_m;
    rotation_rad_ = previous_rotation_rad + a * (rotation_target_rad - previous_rotation_rad);
    if (motion_) {
      // the wall a substep further on; a node that moved far since its rest point was found (a
      // tip that snaps round, a node fed out) finds it again where it now is
      const auto x = rod_.nodes_m();
      for (int i = 0; i < node_count(); ++i) {
        // how far the node moved through the vessel (in its rest frame) since its rest point was found
        if (((x[i] - offset_[i]) - rest_point_m_[i]).squaredNorm() > kRestPointRefreshM * kRestPointRefreshM)
          find_rest_point(i, a0, dt_s);
        offset_[i] = offset_from_[i] + a * (offset_to_[i] - offset_from_[i]);
      }
    }
    // the last substep's impulses are its forces times its length squared: the same forces over this one
    if (last_substep_s_ > 0.0 && h != last_substep_s_) {
      const double scale = (h / last_substep_s_) * (h / last_substep_s_);
      for (Eigen::Vector3d& p : node_impulse_) p *= scale;
      for (Eigen::Vector3d& p : warm_total_) p *= scale;
    }
    place_in_catheter(before_m, h);
    // the solve scheme's warm start: the last substep's wall force in the prediction
    if (params_.rod_contact == RodContactScheme::kSolve)
      for (int i = 0; i < node_count(); ++i)
        rod_.set_node_contact_force_n(
            i, i > rod_.hub_node() ? Eigen::Vector3d(warm_total_[i] / (h * h)) : Eigen::Vector3d::Zero());
    retry_ = false;
    rod_.step(h, lumen_ && contact_ ? this : nullptr);
    if ((retry_ || !rod_.all_finite()) && halvings_ < most) {
      // taken back: the state before it, and half the length
      rod_.restore_state(saved_rod_);
      node_impulse_ = saved_impulse_;
      warm_total_ = saved_warm_total_;
      touched_ = saved_touched_;
      held_ = saved_held_;
      report_ = saved_report_;
      anchor_rest_m_ = saved_anchor_;
      anchored_ = saved_anchored_;
      ++report_.retried;
      fed_m_ = before_m;
      rotation_rad_ = rotation_before_rad;
      ++halvings_;
      // (the stop is decided again before the retry, from the same accepted substep's force)
      good_in_a_row_ = 0;
      continue;
    }
    if (!rod_.all_finite()) recover();
    if (stop_feed) {
      feed_stopped = true;
      refusing_ = true;
    }
    substep_hub_axial_n_ = -rod_.hub_force_n().dot(path_.exit_direction());
    if (!std::isfinite(substep_hub_axial_n_)) substep_hub_axial_n_ = 0.0;
    hub_impulse_n_s += substep_hub_axial_n_ * h;
    done += span;
    last_substep_s_ = h;
    ++report_.substeps;
    report_.finest_halvings = std::max(report_.finest_halvings, halvings_);
    // back to the longer substep after a few good ones, where it fits the grid
    if (halvings_ > 0 && ++good_in_a_row_ >= kGoodSubstepsBeforeLonger && done % (2 * span) == 0) {
      --halvings_;
      good_in_a_row_ = 0;
    }
  }
  rotation_before_step_rad_ = rotation_rad_;

  for (int i = 0; i < node_count(); ++i) {
    wall_force_n_[i] = wall_impulse_n_s_[i] / dt_s;
    wall_force_vector_n_[i] = wall_impulse_vector_n_s_[i] / dt_s;
    // (a substep that went non-finite with no halving left is recovered: its impulses count for nothing)
    if (!std::isfinite(wall_force_n_[i]) || !wall_force_vector_n_[i].allFinite()) {
      wall_force_n_[i] = 0.0;
      wall_force_vector_n_[i].setZero();
    }
  }
  tip_held_ = segment_stuck_.back() != 0;
  // how much shorter the free wire is than the fed length (the wall's projection, not the rod,
  // has the last word in a substep, so a wire driven into a dead end shortens instead of pushing
  // back: docs/guidewire.md)
  {
    const auto x = rod_.nodes_m();
    double free_m = 0.0;
    for (int j = rod_.hub_node(); j < segment_count(); ++j) free_m += (x[j + 1] - x[j]).norm();
    const double nominal_m = (segment_count() - rod_.hub_node()) * rod_.segment_length_m();
    compression_m_ = std::max(nominal_m - free_m, 0.0);
  }
  const Eigen::Vector3d& dir = path_.exit_direction();
  const double previous_axial_n = hub_axial_n_;
  // the rod's force on the hub, against the direction of feed, resists insertion
  hub_axial_n_ = -rod_.hub_force_n().dot(dir);
  mean_hub_axial_n_ = hub_impulse_n_s / dt_s;  // (dt_s > 0: step() returned early otherwise)
  hub_torque_nm_ = -rod_.hub_torque_nm().dot(dir);
  if (!std::isfinite(hub_axial_n_)) hub_axial_n_ = 0.0;
  if (!std::isfinite(hub_torque_nm_)) hub_torque_nm_ = 0.0;
  // how fast the push-back rose with feed: the local force model's stiffness between steps
  const double fed_change_m = fed_m_ - previous_fed_m;
  if (std::abs(fed_change_m) > 1e-6) {
    const double k = (hub_axial_n_ - previous_axial_n) / fed_change_m;
    axial_stiffness_n_per_m_ = std::isfinite(k) ? std::clamp(k, 0.0, params_.axial_stiffness_n_per_m) : 0.0;
  }
}

// a non-finite state (it should not happen; counted): the wire back in the catheter where the
// feed says, the free rod laid straight out of the exit, everything at rest
void RodWire::recover() {
  ++recoveries_;
  // nor friction anchors: the wire is laid out afresh
  std::fill(anchored_.begin(), anchored_.end(), 0);
  // the solve scheme's impulses belong to the state that failed: none carried into the next
  std::fill(held_.begin(), held_.end(), 0);
  std::fill(node_impulse_.begin(), node_impulse_.end(), Eigen::Vector3d::Zero());
  std::fill(warm_total_.begin(), warm_total_.end(), Eigen::Vector3d::Zero());
  const int hub = rod_.hub_node();
  const auto x = rod_.mutable_nodes_m();
  const auto v = rod_.mutable_velocities_m_per_s();
  const auto omega = rod_.mutable_angular_velocities_rad_per_s();
  const auto q = rod_.mutable_orientations();
  const double l = rod_.segment_length_m();
  const Eigen::Vector3d& dir = path_.exit_direction();
  for (int i = 0; i <= hub; ++i) x[i] = path_.point_behind_exit(std::max(params_.length_m - i * l - fed_m_, 0.0));
  for (int i = hub + 1; i < node_count(); ++i) x[i] = x[hub] + (i - hub) * l * dir;
  // the free wire laid out from the hub rides the hub's offset until its rest points are found again
  for (int i = hub + 1; i < node_count(); ++i) {
    offset_[i] = offset_[hub];
    wall_velocity_[i] = wall_velocity_[hub];
  }
  for (int i = 0; i < node_count(); ++i) {
    x[i] += offset_[i];
    v[i] = wall_velocity_[i];
  }
  for (int j = 0; j < segment_count(); ++j) {
    omega[j].setZero();
    const Eigen::Vector3d d = x[j + 1] - x[j];
    q[j] = catheter_frame(j < hub && d.norm() > 1e-12 ? Eigen::Vector3d(d.normalized()) : dir);
  }
  rod_.set_clamp(x[0], q[0]);
}

// [guidewire eq 15]'s condition (a node stays at least the wall margin inside the lumen) as a
// projection along the wall normal, then Coulomb friction decided on forces and applied to the
// motion over the substep (docs/guidewire.md, "Rod: contact and friction"):
//   wall force        N_i = m_i dn_i / h^2    (dn_i: the normal corrections of the substep)
//   rod force on i    f_i = J^T lambda / h^2, its part along the wall f_t
//   stick             |f_t| <= mu_s N_i: the node's motion along the wall this substep is undone
//   slide             else it moves on, and after the substep kinetic friction takes mu_k N h / m
//                     off its velocity along the wall (after_substep)
// and the same about the wire's axis for each touching segment: the constraints' twisting torque
// against mu_s N r holds the frame's spin this substep, or mu_k N r h / I comes off its spin.
// The force test matters for a stiff rod: pushing a wire on needs only a tiny displacement of
// each node, so a displacement test (|dx_t| <= mu_s dn, as for particles) held every touching
// node for ever and the fed wire folded up behind the first bend.
void RodWire::project(rod::CosseratRod& rod, int iteration, double h) {
  if (params_.rod_contact == RodContactScheme::kImplicit) {
    // here only when the direct solve failed and the rod fell back to Gauss-Seidel: the substep
    // is taken back and halved where it may be; else it is finished by the projection (its
    // forces and friction as the projection scheme books them: after_substep)
    if (halvings_ < params_.rod_substep_halvings) {
      retry_ = true;
      return;
    }
    if (iteration == 0) {
      fell_back_ = true;
      std::fill(node_wall_n_.begin(), node_wall_n_.end(), 0.0);
      std::fill(anchored_.begin(), anchored_.end(), 0);
    }
  }
  if (params_.rod_contact == RodContactScheme::kSolve) {
    // the contact problem is not one of the rod's constraints: a further Newton iteration would
    // undo it, so it follows the last one
    if (iteration + 1 == rod.params().iterations) solve_contact(rod, h);
    return;
  }
  const double margin = contact_->wall_margin_m;
  const auto x = rod.mutable_nodes_m();
  const auto x_start = rod.substep_start_nodes_m();
  const int first_free = rod.hub_node() + 1;
  const double inv_h2 = 1.0 / (h * h);
  if (iteration == 0) {
    std::fill(substep_dn_m_.begin(), substep_dn_m_.end(), 0.0);
    std::fill(segment_stuck_.begin(), segment_stuck_.end(), 0);
    std::fill(stuck_.begin(), stuck_.end(), 0);
  }
  for (int i = first_free; i < node_count(); ++i) {
    // what the solve's wall row left (a curved wall is not its tangent plane): back inside. The
    // lumen is described at rest: sampled at the node's rest point, its normal carried unturned
    // (the vessels' motion is a translation over a lumen's width: docs/guidewire.md)
    const WallSample s = lumen_->sample(x[i] - offset_[i]);
    const double dn = s.distance_m + margin;
    if (dn > 0.0) {
      x[i] -= dn * s.normal;
      substep_dn_m_[i] += dn;
    }
    const double wall_n = rod.node_mass_kg(i) * substep_dn_m_[i] * inv_h2;
    if (!(wall_n > 0.0)) continue;
    touched_[i] = 1;
    normal_[i] = s.normal;
    node_wall_n_[i] = wall_n;
    if (!friction_) continue;
    const double mu_s = mu_static(i);
    const Eigen::Vector3d f = rod.node_constraint_force_n(i);
    const Eigen::Vector3d f_t = f - f.dot(s.normal) * s.normal;
    // the node's motion along the wall relative to the wall (which moved wall_velocity_ h)
    const Eigen::Vector3d dx = x[i] - x_start[i] - h * wall_velocity_[i];
    const Eigen::Vector3d dx_t = dx - dx.dot(s.normal) * s.normal;
    if (f_t.norm() <= mu_s * wall_n) {
      x[i] -= dx_t;
      stuck_[i] = 1;
    } else {
      stuck_[i] = 0;  // sliding: kinetic friction slows its velocity after the substep
    }
    // friction moves along the tangent plane, which a curved lumen's wall leaves: back inside
    const WallSample again = lumen_->sample(x[i] - offset_[i]);
    const double dn2 = again.distance_m + margin;
    if (dn2 > 0.0) x[i] -= dn2 * again.normal;
  }
  hold_spin(rod);
}

double RodWire::mu_static(int node) const {
  return !friction_ ? 0.0 : node_in_tip(node) ? friction_->tip_static : friction_->body_static;
}

double RodWire::mu_kinetic(int node) const {
  return !friction_ ? 0.0 : node_in_tip(node) ? friction_->tip_kinetic : friction_->body_kinetic;
}

// the wall's shape operator at a node, S = dn/dx along the wall (central differences of the
// normal in two directions of the tangent plane), symmetric, its convex part dropped (a negative
// stiffness would make the contact problem indefinite)
Eigen::Matrix3d RodWire::wall_shape(const Eigen::Vector3d& p, const Eigen::Vector3d& n) const {
  const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& t : {t1, t2}) {
    const Eigen::Vector3d dn =
        (lumen_->sample(p + kShapeStepM * t).normal - lumen_->sample(p - kShapeStepM * t).normal) / (2.0 * kShapeStepM);
    s += (dn - dn.dot(n) * n) * t.transpose();
  }
  s = 0.5 * (s + s.transpose()).eval();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(s);
  return eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
}

// contact a on the wall where its node stands (at_m, the wall sampled there: s) once moved d_m
// from where it would be without the last substep's force: the tangent plane there,
// gap(d) = distance + margin + n.(d - d_m)
void RodWire::pose_contact(int a, int i, const WallSample& s, const Eigen::Vector3d& at_m, const Eigen::Vector3d& d_m,
                           const Eigen::Vector3d& moved_m, double mu) {
  const Eigen::Vector3d& n = s.normal;
  contacts_[a] = {n, s.distance_m + contact_->wall_margin_m - n.dot(d_m), moved_m - moved_m.dot(n) * n, mu, mu};
  contacts_[a].shape_per_m = wall_shape(at_m - offset_[i], n);
  contacts_[a].linearised_at_m = d_m;
}

// The solve scheme (issue #33), after the rod's last solve of a substep:
//   0. the last substep's wall force was in this substep's prediction (the rod's contact forces,
//      set by step()), so the free solve ends about where the wall holds the rod. (Applied after
//      the free solve instead, a straight wire's tip in a rounded end answered in a growing
//      two-cycle: the linearisation was made where the wire had sprung back off the wall)
//   1. contacts: the free nodes within kContactBandM of the wall there, and those the wall pushed
//      in the last substep (the deepest kMaxRodContacts), each with its wall normal, gap (distance
//      + margin, > 0 inside the wall), its motion along the wall over the substep relative to
//      the wall and the wall's shape operator; the problem is posed as if without the last
//      substep's force (its motion through W taken off the gap and slip)
//   2. W = H A^-1 H^T for them, from the rod's factor
//   3. the contact problem on W (rod::ContactPgs) with the walls' curvature, starting from the
//      last substep's impulses. Each contact has one cone: the static one where static friction
//      held the node in the last accepted substep (its friction strictly inside the cone), else
//      the kinetic one (a node breaks loose on the static cone and slides on the kinetic one from
//      the next substep). Both in one solve, stick within mu_s and slide at mu_k, had no fixed
//      point: the sweeps cycled at their cap, the same contacts flipping stick <-> slip (one cone
//      leaves them converging, though still slowly where W couples a node's normal and tangent);
//      where the answer leaves a node far from where its wall was linearised (its normal turned
//      by more than kReposeTurnRad there, or kReposeM away), posed again on the wall there and
//      solved again
//   4. the rod's response to the change of impulses: multipliers, nodes and frames move together
//   5. what the linearisation leaves inside is moved out along the normal without velocity and
//      reported (a curved wall, or a node the response pushed in that was no contact)
//   6. forces: the wall's on a node is its impulse (curved wall's included) / h^2; the spin rule
//      of the projection scheme is fed with the normal force
void RodWire::solve_contact(rod::CosseratRod& rod, double h) {
  const double margin = contact_->wall_margin_m;
  const auto x = rod.mutable_nodes_m();
  const auto x_start = rod.substep_start_nodes_m();
  const int first_free = rod.hub_node() + 1;
  const double inv_h2 = 1.0 / (h * h);
  std::fill(segment_stuck_.begin(), segment_stuck_.end(), 0);
  std::fill(stuck_.begin(), stuck_.end(), 0);
  std::fill(node_wall_n_.begin(), node_wall_n_.end(), 0.0);
  // 0. the last substep's answer was in the prediction (warm_total_ as the rod's contact
  //    forces: step()), so the free solve starts where the wall held the rod and the contacts are
  //    linearised there; the problem is posed as if without it (its motion d_w = W L_w taken off)
  for (int i = 0; i < first_free; ++i) {
    node_impulse_[i].setZero();  // back in the catheter
    warm_total_[i].setZero();
  }
  for (int i = first_free; i < node_count(); ++i) {
    if (!node_impulse_[i].allFinite() || !warm_total_[i].allFinite()) {
      node_impulse_[i].setZero();
      warm_total_[i].setZero();
    }
    curvature_impulse_[i].setZero();
  }
  // 1. candidates, then the deepest kMaxRodContacts of them in the rod's order
  int count = 0;
  for (int i = first_free; i < node_count(); ++i) {
    const WallSample s = lumen_->sample(x[i] - offset_[i]);
    const double gap = s.distance_m + margin;
    if (!(gap > -kContactBandM) && warm_total_[i].squaredNorm() == 0.0) continue;
    candidates_[count++] = i;
    candidate_gap_m_[i] = gap;
    candidate_wall_[i] = s;
  }
  if (count > kMaxRodContacts) {
    report_.dropped += count - kMaxRodContacts;
    std::nth_element(candidates_.begin(), candidates_.begin() + kMaxRodContacts, candidates_.begin() + count,
                     [&](int a, int b) {
                       // the warm nodes first (their force is in the prediction), then the deepest
                       const bool warm_a = warm_total_[a].squaredNorm() > 0.0;
                       const bool warm_b = warm_total_[b].squaredNorm() > 0.0;
                       return warm_a != warm_b ? warm_a : candidate_gap_m_[a] > candidate_gap_m_[b];
                     });
    count = kMaxRodContacts;
    std::sort(candidates_.begin(), candidates_.begin() + count);
  }
  contact_nodes_.assign(candidates_.begin(), candidates_.begin() + count);
  contacts_.resize(count);
  contact_impulse_.resize(count);
  contact_warm_motion_m_.resize(count);
  contact_moved_m_.resize(count);
  auto w = compliance_.topLeftCorner(3 * count, 3 * count);
  const bool have_w = count > 0 && rod.contact_compliance(contact_nodes_, w);
  for (int a = 0; a < count && have_w; ++a) {
    const int i = contact_nodes_[a];
    // the problem is posed as if without the last substep's force: what it moved the node through
    // W comes off its gap and slip (the wall, and its curvature, linearised where the node stands now)
    Eigen::Vector3d warm_motion = Eigen::Vector3d::Zero();
    for (int b = 0; b < count; ++b) warm_motion += w.block<3, 3>(3 * a, 3 * b) * warm_total_[contact_nodes_[b]];
    const Eigen::Vector3d moved = x[i] - x_start[i] - h * wall_velocity_[i] - warm_motion;
    pose_contact(a, i, candidate_wall_[i], x[i], warm_motion, moved, held_[i] ? mu_static(i) : mu_kinetic(i));
    contact_warm_motion_m_[a] = warm_motion;
    contact_moved_m_[a] = moved;
    contact_impulse_[a] = node_impulse_[i];  // the solver starts from the warm impulse
  }
  // the linearisation is a short substep's: a contact that moved far relative to its wall, or
  // whose wall turned under it, asks for the substep to be taken back and halved
  const bool may_retry = halvings_ < params_.rod_substep_halvings;
  const double cos_turn = std::cos(kRetryTurnDeg * std::numbers::pi / 180.0);
  for (int a = 0; a < count && have_w && may_retry; ++a) {
    const int i = contact_nodes_[a];
    const Eigen::Vector3d moved = x[i] - x_start[i] - h * wall_velocity_[i];
    const Eigen::Vector3d began_at = x_start[i] - (offset_[i] - h * wall_velocity_[i]);
    if (moved.squaredNorm() > kRetryMotionM * kRetryMotionM ||
        lumen_->sample(began_at).normal.dot(contacts_[a].normal) < cos_turn) {
      retry_ = true;
      return;
    }
  }
  report_.contacts = count;
  report_.most_contacts = std::max(report_.most_contacts, count);
  // 2-4: the answer, applied as its change from the warm impulses
  if (have_w) {
    rod::ContactSolveStats st = pgs_.solve(w, contacts_, contact_impulse_, kContactSweeps, kContactToleranceM);
    // the answer moves a node far from where its wall was linearised (the last substep's force,
    // in the prediction, can carry a light node millimetres away when this substep's force is
    // far smaller): posed again on the wall where the answer leaves it, and solved again from the
    // answer's impulses (the curved walls' start again from none). (A contact posed again is not
    // checked again for a retry: the checks above ran where the free solve left it.)
    for (int round = 0; round < kReposeRounds; ++round) {
      bool far = false;
      for (int a = 0; a < count; ++a) {
        const Eigen::Vector3d d = pgs_.motion_m()[a];
        const Eigen::Vector3d drift = d - contacts_[a].linearised_at_m;
        if (drift.squaredNorm() <= kReposeM * kReposeM &&
            drift.norm() * contacts_[a].shape_per_m.norm() <= kReposeTurnRad)
          continue;
        far = true;
        const int i = contact_nodes_[a];
        const Eigen::Vector3d at = x[i] + d - contact_warm_motion_m_[a];
        pose_contact(a, i, lumen_->sample(at - offset_[i]), at, d, contact_moved_m_[a], contacts_[a].mu_static);
      }
      if (!far) break;
      report_.most_sweeps = std::max(report_.most_sweeps, st.sweeps);
      st = pgs_.solve(w, contacts_, contact_impulse_, kContactSweeps, kContactToleranceM);
    }
    report_.most_sweeps = std::max(report_.most_sweeps, st.sweeps);
    report_.unconverged += st.converged ? 0 : 1;
    // applied: the answer and the curved wall's impulse, less what the prediction had of them
    for (int a = 0; a < count; ++a) {
      const int i = contact_nodes_[a];
      node_impulse_[i] = contact_impulse_[a];
      curvature_impulse_[i] = pgs_.curvature_impulses()[a];
      contact_impulse_[a] += curvature_impulse_[i] - warm_total_[i];
    }
    rod.apply_contact_impulses(contact_nodes_, contact_impulse_);
    for (int a = 0; a < count; ++a) contact_impulse_[a] = node_impulse_[contact_nodes_[a]];
  }
  // kept for the next substep: the answer (the contact problem's warm start) and with the
  // curvature's impulse (the prediction's force); the wall's force on a node is both (after_substep)
  std::fill(node_impulse_.begin(), node_impulse_.end(), Eigen::Vector3d::Zero());
  std::fill(warm_total_.begin(), warm_total_.end(), Eigen::Vector3d::Zero());
  std::fill(held_.begin(), held_.end(), 0);  // (a retried substep restores them)
  if (have_w) {
    for (int a = 0; a < count; ++a) {
      const int i = contact_nodes_[a];
      const Eigen::Vector3d& n = contacts_[a].normal;
      const double push = -n.dot(contact_impulse_[a]);
      if (!(push > 0.0)) {
        curvature_impulse_[i].setZero();
        continue;
      }
      node_impulse_[i] = contact_impulse_[a];
      warm_total_[i] = node_impulse_[i] + curvature_impulse_[i];
      touched_[i] = 1;
      normal_[i] = n;
      node_wall_n_[i] = push * inv_h2;  // after_substep adds it (and node_impulse_) to the step's impulse
      const Eigen::Vector3d slip = contacts_[a].slip_m + pgs_.motion_m()[a];
      stuck_[i] = (slip - slip.dot(n) * n).norm() < kStuckM;
      // held by static friction: the answer's friction strictly inside this substep's cone
      const Eigen::Vector3d friction = node_impulse_[i] + push * n;
      held_[i] = friction.norm() < (1.0 - 1e-6) * contacts_[a].mu_static * push;
    }
  }
  // 5. the linearisation's leftovers, out along the normal, without velocity (or, where a node
  //    was left deep inside, the substep taken back and halved)
  double residual_m = 0.0;
  for (int i = first_free; i < node_count(); ++i) {
    const WallSample s = lumen_->sample(x[i] - offset_[i]);
    const double dn = s.distance_m + margin;
    if (dn <= 0.0) continue;
    residual_m = std::max(residual_m, dn);
    rod.shift_node_without_velocity(i, -dn * s.normal);
  }
  if (residual_m > kRetryResidualM && may_retry) {
    retry_ = true;
    return;
  }
  report_.residual_m = std::max(report_.residual_m, residual_m);
  // 6. the spin about the wire's axis
  hold_spin(rod);
}

// The implicit scheme (issue #33): after the prediction (round 0) and after each solve, the
// springs of every free node, placed where it stands (CosseratRod::set_node_spring):
//   depth        d = distance to the wall + margin (> 0: inside the margin)
//   wall         K_n = k n n^T towards the wall point x - d n: force k d along -n where d > 0,
//                none where d <= 0 (one-sided: a node that ended outside is let go)
//   friction     K_t = k_t (I - n n^T) towards the anchor b (where the node stuck): the stuck
//                spring k_t = k holds it while k |x - b|_t <= mu_s N (N = k d); else it slides
//                and k_t = mu_k N / |x - b|_t, a spring whose force is mu_k N against the slip
//                (a Coulomb law as a sequence of linear ones: the stiffness found again each round)
// The springs placed after a solve are the next solve's; the force of those the last solve ran
// with is kept (spring_force_n_). Returns whether to solve again: a node moved more than
// kSpringSettledM since its springs were placed, or one came into or out of contact.
bool RodWire::place_springs(rod::CosseratRod& rod, int round, double h) {
  const double margin = contact_->wall_margin_m;
  const double k = params_.rod_wall_stiffness_n_per_m;
  const auto x = rod.nodes_m();
  const auto x_start = rod.substep_start_nodes_m();
  const int first_free = rod.hub_node() + 1;
  if (round == 0) {
    fell_back_ = false;
    // a node that begins the substep deep in the wall: back to kSpringDeepM, without velocity
    const auto x_begin = rod.substep_start_nodes_m();
    for (int i = first_free; i < node_count(); ++i) {
      const WallSample s = lumen_->sample(x_begin[i] - (offset_[i] - h * wall_velocity_[i]));
      const double too_deep = s.distance_m + margin - kSpringDeepM;
      if (too_deep > 0.0) rod.shift_node_without_velocity(i, -too_deep * s.normal);
    }
    std::fill(stuck_.begin(), stuck_.end(), 0);
    std::fill(segment_stuck_.begin(), segment_stuck_.end(), 0);
    std::fill(node_wall_n_.begin(), node_wall_n_.end(), 0.0);
    for (int i = 0; i < first_free; ++i) {
      rod.clear_node_spring(i);
      anchored_[i] = 0;
    }
  } else {
    // what the last solve's springs did: the wall's force on each node, and whether it stuck
    for (int i = first_free; i < node_count(); ++i) {
      spring_force_n_[i] = rod.node_spring_force_n(i);
      const double push = -spring_force_n_[i].dot(spring_normal_[i]);
      node_wall_n_[i] = rod.has_node_spring(i) && push > 0.0 ? push : 0.0;
      stuck_[i] = node_wall_n_[i] > 0.0 && spring_stuck_[i];
    }
  }
  // the last round: its solve stands; the spin about the wire's axis as the projection holds it
  const auto finish = [&] {
    // a node the last solve left deep in the wall with no spring: the substep is too long here
    if (halvings_ < params_.rod_substep_halvings) {
      for (int i = first_free; i < node_count() && !retry_; ++i)
        retry_ = !rod.has_node_spring(i) && lumen_->sample(x[i] - offset_[i]).distance_m + margin > kSpringDeepM;
      if (retry_) return false;
    }
    int contacts = 0;
    for (int i = first_free; i < node_count(); ++i) {
      if (!(node_wall_n_[i] > 0.0)) continue;
      touched_[i] = 1;
      normal_[i] = spring_normal_[i];
      ++contacts;
      // how deep into the margin the wall's spring holds the node (N / k where it settled)
      report_.residual_m = std::max(report_.residual_m, node_wall_n_[i] / k);
    }
    report_.contacts = contacts;
    report_.most_contacts = std::max(report_.most_contacts, contacts);
    report_.most_sweeps = std::max(report_.most_sweeps, round);  // the solves the substep took
    hold_spin(rod);
    return false;
  };
  if (round >= params_.rod_contact_rounds) {
    // the springs have not settled: a spring that pulls its node (it ended off the wall) is let
    // go and the substep solved once more without it (left in, it pulled the hub: a 6 N step in
    // the dead end); then the last solve stands
    bool pulling = false;
    for (int i = first_free; i < node_count() && round == params_.rod_contact_rounds; ++i) {
      if (!rod.has_node_spring(i) || node_wall_n_[i] > 0.0) continue;
      rod.clear_node_spring(i);
      pulling = true;
    }
    if (pulling) return true;
    ++report_.unconverged;
    return finish();
  }
  bool again = false;
  for (int i = first_free; i < node_count(); ++i) {
    // where the spring is linearised: after a solve, where the node ended; before the first, where
    // it began the substep (carried with the wall), not its prediction: a light node's prediction
    // under a dead force may lie far outside (the capstan's leader on the tip: 0.44 m a substep),
    // which only the rod's constraints bring back
    const Eigen::Vector3d p = round == 0 ? Eigen::Vector3d(x_start[i] + h * wall_velocity_[i]) : x[i];
    const WallSample s = lumen_->sample(p - offset_[i]);
    const double d = s.distance_m + margin;
    const bool was_on = rod.has_node_spring(i);
    if (!(d > 0.0)) {
      if (was_on) {
        rod.clear_node_spring(i);
        again = again || (round > 0);
      }
      continue;
    }
    const bool moved = (p - spring_at_m_[i]).squaredNorm() > kSpringSettledM * kSpringSettledM;
    again = again || (round > 0 && (!was_on || moved));
    spring_at_m_[i] = p;
    const Eigen::Vector3d& n = s.normal;
    spring_normal_[i] = n;
    const Eigen::Matrix3d nn = n * n.transpose();
    const Eigen::Vector3d wall_point = p - d * n;
    Eigen::Matrix3d stiffness = k * nn;
    Eigen::Vector3d anchor = wall_point;
    spring_stuck_[i] = 0;
    if (friction_) {
      // a node that comes to the wall sticks where its substep began (relative to the wall)
      if (!anchored_[i]) {
        anchor_rest_m_[i] = x_start[i] - (offset_[i] - h * wall_velocity_[i]);
        anchored_[i] = 1;
      }
      const Eigen::Vector3d b = anchor_rest_m_[i] + offset_[i];
      const Eigen::Vector3d slip = (Eigen::Matrix3d::Identity() - nn) * (p - b);
      const double wall_n = k * d, slip_m = slip.norm();
      double k_t = k;
      if (k * slip_m <= mu_static(i) * wall_n) {
        spring_stuck_[i] = 1;
      } else {
        k_t = std::min(
            k, mu_kinetic(i) * wall_n /
                   slip_m);  // (mu_k above mu_s: no stiffer than stuck)  // (mu_k above mu_s: no stiffer than stuck)
      }
      stiffness += k_t * (Eigen::Matrix3d::Identity() - nn);
      anchor = b + n * n.dot(wall_point - b);
    }
    rod.set_node_spring(i, stiffness, anchor);
  }
  if (round > 0 && !again) return finish();
  return round == 0 || again;
}

// after an implicit substep: a node that slid drags its friction anchor behind it (to where the
// stuck spring would pull with mu_k N); a node off the wall lets go of its anchor
void RodWire::commit_anchors(rod::CosseratRod& rod, double /*h*/) {
  const auto x = rod.nodes_m();
  const double k = params_.rod_wall_stiffness_n_per_m;
  for (int i = rod.hub_node() + 1; i < node_count(); ++i) {
    if (!(node_wall_n_[i] > 0.0)) {
      anchored_[i] = 0;
      continue;
    }
    if (!friction_ || stuck_[i]) continue;
    const Eigen::Vector3d& n = spring_normal_[i];
    const Eigen::Vector3d b = anchor_rest_m_[i] + offset_[i];
    Eigen::Vector3d slip = x[i] - b;
    slip -= slip.dot(n) * n;
    const double slip_m = slip.norm(), behind_m = mu_kinetic(i) * node_wall_n_[i] / k;
    if (slip_m > behind_m) anchor_rest_m_[i] += (1.0 - behind_m / slip_m) * slip;
  }
}

// about the wire's axis: a segment touches where either of its nodes does; its constraints'
// twisting torque against mu_s N r holds the frame's spin this substep
void RodWire::hold_spin(rod::CosseratRod& rod) {
  if (!friction_) return;
  const int first_free = rod.hub_node() + 1;
  const auto q = rod.mutable_orientations();
  const auto q_start = rod.substep_start_orientations();
  const double r = 0.5 * params_.outer_diameter_m;
  for (int j = rod.hub_node(); j < segment_count(); ++j) {
    double wall_n = 0.0;
    for (int i : {j, j + 1})
      if (i >= first_free && touched_[i]) wall_n += 0.5 * node_wall_n_[i];
    if (wall_n <= 0.0) continue;
    const double mu_s = mu_static(j + 1);
    const Eigen::Vector3d axis = q[j] * Eigen::Vector3d::UnitZ();
    // the frame's turn about its axis since the substep began (swing-twist: the twist part)
    Eigen::Quaterniond turn = q[j] * q_start[j].conjugate();
    if (turn.w() < 0.0) turn.coeffs() = -turn.coeffs();
    const double spin = 2.0 * std::atan2(turn.vec().dot(axis), turn.w());
    const double torque = rod.segment_constraint_torque_nm(j).dot(axis);
    segment_stuck_[j] = std::abs(torque) <= mu_s * wall_n * r;
    if (segment_stuck_[j]) q[j] = Eigen::Quaterniond(Eigen::AngleAxisd(-spin, axis)) * q[j];
  }
}

// kinetic friction on what slides: the wall's friction impulse over the substep, mu_k N h,
// taken off the velocity along the wall (never reversing it), and mu_k N r h off the spin
void RodWire::after_substep(rod::CosseratRod& rod, double h) {
  const int first_free = rod.hub_node() + 1;
  // a substep that went non-finite is taken back too, where it may be
  if (!retry_ && params_.rod_contact != RodContactScheme::kProjection && halvings_ < params_.rod_substep_halvings &&
      !rod.all_finite())
    retry_ = true;
  if (retry_) {
    // the substep is taken back (step()): nothing of it counts
    std::fill(node_wall_n_.begin(), node_wall_n_.end(), 0.0);
    return;
  }
  // the rod's damping is blood's drag, and the blood moves with its vessel: relative to a moving
  // wall, v = wall + keep (v - wall), where the rod applied v = keep v (keep: the node's own, a
  // heavier soft tip's included)
  if (motion_) {
    const auto v = rod.mutable_velocities_m_per_s();
    for (int i = first_free; i < node_count(); ++i)
      v[i] += (1.0 - 1.0 / (1.0 + rod.node_damping_per_s(i) * h)) * wall_velocity_[i];
  }
  // the wall's impulse over the substep, for the step's average force: the solve scheme's as its
  // impulse (force h^2: normal and friction), the projection's along the wall's inward normal
  const bool solve = params_.rod_contact == RodContactScheme::kSolve;
  // (an implicit substep that fell back to the projection is booked as the projection's)
  const bool implicit = params_.rod_contact == RodContactScheme::kImplicit && !fell_back_;
  for (int i = first_free; i < node_count(); ++i) {
    if (!(node_wall_n_[i] > 0.0)) continue;
    wall_impulse_n_s_[i] += node_wall_n_[i] * h;
    wall_impulse_vector_n_s_[i] += solve      ? Eigen::Vector3d((node_impulse_[i] + curvature_impulse_[i]) / h)
                                   : implicit ? Eigen::Vector3d(spring_force_n_[i] * h)
                                              : Eigen::Vector3d(-node_wall_n_[i] * h * normal_[i]);
  }
  if (implicit) commit_anchors(rod, h);
  if (friction_) {
    const auto v = rod.mutable_velocities_m_per_s();
    const auto omega = rod.mutable_angular_velocities_rad_per_s();
    // (the solve and implicit schemes' friction on the nodes is in their solves)
    for (int i = first_free; i < node_count() && !solve && !implicit; ++i) {
      if (!(node_wall_n_[i] > 0.0) || stuck_[i]) continue;
      const double mu_k = mu_kinetic(i);
      const Eigen::Vector3d& n = normal_[i];
      const Eigen::Vector3d v_rel = v[i] - wall_velocity_[i];
      const Eigen::Vector3d v_t = v_rel - v_rel.dot(n) * n;
      const double speed = v_t.norm();
      const double slow = mu_k * node_wall_n_[i] * h / rod.node_mass_kg(i);
      if (speed > 0.0) v[i] -= std::min(1.0, slow / speed) * v_t;
    }
    const double r = 0.5 * params_.outer_diameter_m;
    for (int j = rod.hub_node(); j < segment_count(); ++j) {
      if (segment_stuck_[j]) {
        omega[j].z() = 0.0;
        continue;
      }
      double wall_n = 0.0;
      for (int i : {j, j + 1})
        if (i >= first_free) wall_n += 0.5 * node_wall_n_[i];
      if (wall_n <= 0.0) continue;
      const double mu_k = mu_kinetic(j + 1);
      const double slow = mu_k * wall_n * r * h / rod.segment_inertia_kg_m2(j);
      omega[j].z() -= std::copysign(std::min(std::abs(omega[j].z()), slow), omega[j].z());
    }
  }
  std::fill(node_wall_n_.begin(), node_wall_n_.end(), 0.0);
}

double RodWire::tip_roll_rad() const {
  // the twist summed over the pairs from the hub to the tip: how far the tip's frame has turned
  // about the wire relative to the hub's (negative: it lags a positive turn)
  const auto q = rod_.orientations();
  double twist = 0.0;
  for (int j = rod_.hub_node(); j < segment_count(); ++j) {
    Eigen::Quaterniond rel = rod_.pair_first_frame(j).conjugate() * q[j];
    if (rel.w() < 0.0) rel.coeffs() = -rel.coeffs();
    twist += 2.0 * std::atan2(rel.z(), rel.w());
  }
  return twist;
}

double RodWire::refused_feed_m() const {
  return refusing_ ? std::max(commanded_feed_m_ - fed_m_, 0.0) : 0.0;
}

WireFeedback RodWire::feedback() const {
  WireFeedback f;
  const double refused = refused_feed_m();
  // the rod's own push-back at the hub, and the grip's spring while feed is refused
  f.internal_n = hub_axial_n_ + params_.axial_stiffness_n_per_m * std::max(refused, 0.0);
  f.stiffness_n_per_m = refused > 1e-9 ? params_.axial_stiffness_n_per_m : axial_stiffness_n_per_m_;
  f.elastic_torque_nm = hub_torque_nm_;
  // while static friction holds the tip, turning the hub winds up the free wire: its torsion
  // springs in series (the soft tip's included); a free tip spins with no such spring
  if (tip_held_) {
    double compliance = 0.0;
    for (int j = rod_.hub_node(); j < segment_count(); ++j)
      compliance += rod_.dual_length_m(j) / rod_.bend_twist_stiffness(j).z();
    if (compliance > 0.0) f.torsion_stiffness_nm_per_rad = 1.0 / compliance;
  }
  return f;
}

}  // namespace pcisim::physics
