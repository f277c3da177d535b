#include "physics/rod/cosserat_rod.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "physics/rod/cosserat_constraints.h"

namespace pcisim::physics::rod {
namespace {

void require(bool ok, const char* field, const char* range) {
  if (!ok) throw std::invalid_argument(std::string("rod: ") + field + " must be in " + range);
}

bool positive(double v) {
  return std::isfinite(v) && v > 0.0;
}

}  // namespace

void validate(const CosseratRodParams& p) {
  require(positive(p.length_m) && p.length_m <= 10.0, "length_m", "(0, 10]");
  require(p.segments >= 1 && p.segments <= 10000, "segments", "[1, 10000]");
  require(positive(p.bending_stiffness_nm2), "bending_stiffness_nm2", "(0, inf)");
  require(positive(p.torsional_stiffness_nm2), "torsional_stiffness_nm2", "(0, inf)");
  require(positive(p.axial_stiffness_n), "axial_stiffness_n", "(0, inf)");
  require(positive(p.shear_stiffness_n), "shear_stiffness_n", "(0, inf)");
  require(positive(p.mass_per_length_kg_per_m), "mass_per_length_kg_per_m", "(0, inf)");
  require(std::isfinite(p.outer_diameter_m) && p.outer_diameter_m >= 0.0, "outer_diameter_m", "[0, inf)");
  require(std::isfinite(p.tip_mass_scale) && p.tip_mass_scale >= 1.0 && p.tip_mass_scale <= 1e6, "tip_mass_scale",
          "[1, 1e6]");
  require(std::isfinite(p.rotational_inertia_scale) && p.rotational_inertia_scale >= 1.0 &&
              p.rotational_inertia_scale <= 1e9,
          "rotational_inertia_scale", "[1, 1e9]");
  require(std::isfinite(p.damping_per_s) && p.damping_per_s >= 0.0, "damping_per_s", "[0, inf)");
  require(p.substeps >= 1 && p.substeps <= 10000, "substeps", "[1, 10000]");
  require(std::isfinite(p.max_substep_s) && p.max_substep_s > 0.0, "max_substep_s", "(0, inf)");
  require(p.iterations >= 1 && p.iterations <= 10000, "iterations", "[1, 10000]");
  require(std::isfinite(p.stretch_guard) && p.stretch_guard >= 0.0 && p.stretch_guard <= 1.0, "stretch_guard",
          "[0, 1]");
  require(p.gravity_m_per_s2.allFinite(), "gravity_m_per_s2", "finite values");
  require(std::isfinite(p.tip_length_m) && p.tip_length_m >= 0.0 && p.tip_length_m <= p.length_m, "tip_length_m",
          "[0, length_m]");
  require(positive(p.tip_stiffness_ratio) && p.tip_stiffness_ratio <= 1e6, "tip_stiffness_ratio", "(0, 1e6]");
}

CosseratRod::CosseratRod(const CosseratRodParams& params, const Eigen::Vector3d& clamp_position_m,
                         const Eigen::Quaterniond& clamp_orientation)
    : params_(params),
      n_(params.segments),
      l_(0.0),
      clamp_q_(clamp_orientation.normalized()),
      system_(params.solver == RodSolver::kDirect ? std::max(params.segments, 1) : 0) {
  validate(params_);
  l_ = params_.length_m / n_;
  const int nodes = n_ + 1;
  x_.resize(nodes);
  x_old_.resize(nodes);
  v_.assign(nodes, Eigen::Vector3d::Zero());
  force_.assign(nodes, Eigen::Vector3d::Zero());
  contact_force_.assign(nodes, Eigen::Vector3d::Zero());
  mass_.resize(nodes);
  inv_mass_.resize(nodes);
  q_.assign(n_, clamp_q_);
  q_old_.assign(n_, clamp_q_);
  omega_.assign(n_, Eigen::Vector3d::Zero());
  inv_inertia_q_.resize(n_);
  ss_stiffness_.resize(n_);
  ss_compliance_.resize(n_);
  ss_lambda_.assign(n_, Eigen::Vector3d::Zero());
  bt_stiffness_.resize(n_);
  bt_compliance_.resize(n_);
  bt_lambda_.assign(n_, Eigen::Vector3d::Zero());
  rest_darboux_.assign(n_, Eigen::Vector3d::Zero());  // straight at rest
  if (params_.solver == RodSolver::kDirect) {
    rhs_.assign(n_, BlockTridiagonal6::Vector::Zero());
    dlambda_.assign(n_, BlockTridiagonal6::Vector::Zero());
    column_rhs_.assign(n_, BlockTridiagonal6::Columns3::Zero());
    column_.assign(n_, BlockTridiagonal6::Columns3::Zero());
    ss_jacobian_.assign(n_, Eigen::Matrix3d::Zero());
    bt_jacobian_.assign(n_, Eigen::Matrix3d::Zero());
  }

  spring_on_.assign(nodes, 0);
  spring_k_.assign(nodes, Eigen::Matrix3d::Zero());
  spring_w_.assign(nodes, Eigen::Matrix3d::Zero());
  spring_anchor_.assign(nodes, Eigen::Vector3d::Zero());
  x_pred_.assign(nodes, Eigen::Vector3d::Zero());
  q_pred_.assign(n_, clamp_q_);

  const Eigen::Vector3d tangent = clamp_q_ * Eigen::Vector3d::UnitZ();
  const double mu = params_.mass_per_length_kg_per_m;
  const double r = 0.5 * params_.outer_diameter_m;
  const double tip_start_m = params_.length_m - params_.tip_length_m;
  own_mass_share_.assign(nodes, 1.0);
  for (int i = 0; i < nodes; ++i) {
    x_[i] = clamp_position_m + (i * l_) * tangent;
    mass_[i] = (i == n_ ? 0.5 : 1.0) * mu * l_;
    // the soft tip's nodes, from the one where it begins: heavier for their motion, not their weight
    if (params_.tip_length_m > 0.0 && i * l_ >= tip_start_m - 1e-12 * params_.length_m) {
      mass_[i] *= params_.tip_mass_scale;
      own_mass_share_[i] = 1.0 / params_.tip_mass_scale;
    }
    inv_mass_[i] = i == 0 ? 0.0 : 1.0 / mass_[i];  // node 0 is clamped
  }
  const double inertia = params_.rotational_inertia_scale * mu * l_ * (l_ * l_ / 12.0 + r * r / 4.0);
  for (int j = 0; j < n_; ++j) {
    inv_inertia_q_[j] = 1.0 / (4.0 * inertia);
    const double ga = params_.shear_stiffness_n, ea = params_.axial_stiffness_n;
    ss_stiffness_[j] = {ga, ga, ea};
    ss_compliance_[j] = ss_stiffness_[j].cwiseInverse() / l_;
    // pair j sits at s = j l: in the tip when beyond the tip's start (and the tip is not empty)
    const double s = j * l_;
    const bool tip = params_.tip_length_m > 0.0 && s > tip_start_m + 1e-12 * params_.length_m;
    const double scale = tip ? params_.tip_stiffness_ratio : 1.0;
    const double ei = scale * params_.bending_stiffness_nm2, gj = scale * params_.torsional_stiffness_nm2;
    bt_stiffness_[j] = {ei, ei, gj};
    bt_compliance_[j] = bt_stiffness_[j].cwiseInverse();
  }
}

void CosseratRod::set_node_force_n(int node, const Eigen::Vector3d& force_n) {
  if (node < 0 || node > n_) throw std::out_of_range("rod: node index out of range");
  force_[node] = force_n;
}

void CosseratRod::set_node_contact_force_n(int node, const Eigen::Vector3d& force_n) {
  if (node < 0 || node > n_) throw std::out_of_range("rod: node index out of range");
  contact_force_[node] = force_n;
}

void CosseratRod::clear_node_forces() {
  std::fill(force_.begin(), force_.end(), Eigen::Vector3d::Zero());
}

void CosseratRod::set_node_spring(int node, const Eigen::Matrix3d& k_n_per_m, const Eigen::Vector3d& anchor_m) {
  if (node < 0 || node > n_) throw std::out_of_range("rod: node index out of range");
  spring_on_[node] = 1;
  spring_k_[node] = 0.5 * (k_n_per_m + k_n_per_m.transpose());
  spring_anchor_[node] = anchor_m;
}

void CosseratRod::clear_node_spring(int node) {
  if (node < 0 || node > n_) throw std::out_of_range("rod: node index out of range");
  spring_on_[node] = 0;
}

Eigen::Vector3d CosseratRod::node_spring_force_n(int node) const {
  if (node <= hub_ || node > n_ || !spring_on_[node]) return Eigen::Vector3d::Zero();
  return -spring_k_[node] * (x_[node] - spring_anchor_[node]);
}

Eigen::Matrix3d CosseratRod::node_inverse_mass(int i) const {
  if (springs_in_solve_ && spring_on_[i] && inv_mass_[i] > 0.0) return spring_w_[i];
  return inv_mass_[i] * Eigen::Matrix3d::Identity();
}

void CosseratRod::set_clamp(const Eigen::Vector3d& position_m, const Eigen::Quaterniond& orientation) {
  x_[0] = position_m;
  clamp_q_ = orientation.normalized();
}

void CosseratRod::set_hub_node(int hub_node) {
  if (hub_node < 0 || hub_node >= n_) throw std::out_of_range("rod: hub node out of range");
  hub_ = hub_node;
  for (int i = 0; i <= n_; ++i) inv_mass_[i] = i <= hub_ ? 0.0 : 1.0 / mass_[i];
}

void CosseratRod::set_rest_darboux_per_m(int pair, const Eigen::Vector3d& darboux_per_m) {
  if (pair < 0 || pair >= n_) throw std::out_of_range("rod: pair index out of range");
  rest_darboux_[pair] = darboux_per_m;
}

Eigen::Vector3d CosseratRod::hub_force_n() const {
  if (!direct_ran_ || !(last_h_ > 0.0)) return Eigen::Vector3d::Zero();
  // segment hub's stretch-shear pulls its first node (the hub) with J_p1^T lambda = -lambda / l
  return -ss_lambda_[hub_] / (l_ * last_h_ * last_h_);
}

Eigen::Vector3d CosseratRod::hub_torque_nm() const {
  if (!direct_ran_ || !(last_h_ > 0.0)) return Eigen::Vector3d::Zero();
  // pair hub's bend-twist turns its first frame (the hub's) with -B^T lambda (B as solved with)
  return -bt_jacobian_[hub_].transpose() * bt_lambda_[hub_] / (last_h_ * last_h_);
}

Eigen::Vector3d CosseratRod::node_constraint_force_n(int i) const {
  if (!direct_ran_ || !(last_h_ > 0.0) || i <= hub_) return Eigen::Vector3d::Zero();
  // node i ends segment i - 1 (J = I / l) and starts segment i (J = -I / l)
  Eigen::Vector3d f = ss_lambda_[i - 1];
  if (i < n_) f -= ss_lambda_[i];
  return f / (l_ * last_h_ * last_h_);
}

Eigen::Vector3d CosseratRod::segment_constraint_torque_nm(int j) const {
  if (!direct_ran_ || !(last_h_ > 0.0) || j < hub_) return Eigen::Vector3d::Zero();
  // frame j is pair j's second (B_j) and pair j + 1's first (-B_{j+1}); its stretch-shear term
  // [d3]x^T lambda has no part about d3 and is kept for completeness
  Eigen::Vector3d t = ss_jacobian_[j].transpose() * ss_lambda_[j] + bt_jacobian_[j].transpose() * bt_lambda_[j];
  if (j + 1 < n_) t -= bt_jacobian_[j + 1].transpose() * bt_lambda_[j + 1];
  return t / (last_h_ * last_h_);
}

void CosseratRod::step(double dt_s, RodContact* contact) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return;
  // a longer step than the rod was tuned for takes more substeps (no substep longer than
  // max_substep_s): one linearised solve from a prediction h^2 a away is only good for small h
  const int substeps =
      std::max(params_.substeps, static_cast<int>(std::min(std::ceil(dt_s / params_.max_substep_s - 1e-9), 10000.0)));
  const double h = dt_s / substeps;
  last_h_ = h;
  for (int sub = 0; sub < substeps; ++sub) {
    predict(h);
    const bool springs = params_.solver == RodSolver::kDirect && contact && contact->uses_springs();
    if (params_.solver != RodSolver::kDirect ||
        !(springs ? solve_with_springs(h, contact) : solve_constraints_direct(h, contact))) {
      direct_ran_ = false;  // the multipliers are Gauss-Seidel's now (material frame)
      solve_constraints(h, contact);
    }
    guard_stretch();
    update_velocities(h);
    if (contact) contact->after_substep(*this, h);
  }
}

// symplectic Euler prediction of the free nodes and the segments' frames
void CosseratRod::predict(double h) {
  for (int i = 0; i <= n_; ++i) {
    x_old_[i] = x_[i];
    if (inv_mass_[i] == 0.0) continue;
    v_[i] += h * (own_mass_share_[i] * params_.gravity_m_per_s2 + inv_mass_[i] * (force_[i] + contact_force_[i]));
    x_[i] += h * v_[i];
  }
  for (int j = 0; j < n_; ++j) {
    q_old_[j] = q_[j];
    if (j < hub_) continue;  // kinematic
    // dq/dt = 1/2 q (0, omega) with omega in the material frame (isotropic inertia: no gyroscopic term)
    const Eigen::Quaterniond w(0.0, omega_[j].x(), omega_[j].y(), omega_[j].z());
    q_[j].coeffs() += 0.5 * h * (q_[j] * w).coeffs();
    q_[j].normalize();
  }
}

void CosseratRod::solve_constraints(double h, RodContact* contact) {
  const double inv_h2 = 1.0 / (h * h);
  for (int j = 0; j < n_; ++j) {
    ss_lambda_[j].setZero();
    bt_lambda_[j].setZero();
  }
  const int f = hub_;
  for (int it = 0; it < params_.iterations; ++it) {
    for (int j = f; j < n_; ++j) {
      project_stretch_shear(x_[j], inv_mass_[j], x_[j + 1], inv_mass_[j + 1], q_[j], inv_inertia_q_[j], l_,
                            ss_compliance_[j] * inv_h2, ss_lambda_[j]);
    }
    // pair f: the hub's frame (immovable: the clamp frame at hub 0, over half a segment) and segment f
    Eigen::Quaterniond hub_frame = pair_first_frame(f);
    project_bend_twist(hub_frame, 0.0, q_[f], inv_inertia_q_[f], dual_length_m(f), rest_darboux_[f],
                       bt_compliance_[f] * (inv_h2 / dual_length_m(f)), bt_lambda_[f]);
    for (int j = f + 1; j < n_; ++j) {
      project_bend_twist(q_[j - 1], inv_inertia_q_[j - 1], q_[j], inv_inertia_q_[j], l_, rest_darboux_[j],
                         bt_compliance_[j] * (inv_h2 / dual_length_m(j)), bt_lambda_[j]);
    }
    if (contact) contact->project(*this, it, h);
  }
}

// The XPBD system of every constraint at once (Macklin et al. 2016, eq 18 for all constraints
// together; Deul et al. 2018 for rods): per iteration, the linearised update of the multipliers
//   (J W J^T + alpha~) dlambda = -(C + alpha~ lambda)
// with J the constraints' Jacobians (cosserat_constraints.h) over the node positions and each
// frame's world rotation, W the inverse node masses and inverse rotational inertias. Ordered by
// segment, unit j = (stretch-shear j, bend-twist j), the matrix is block tridiagonal: segment j's
// constraints share node j + 1 and frame j with segment j + 1's and nothing further. Then
//   dx = W J^T dlambda,  q <- normalise(q + 1/2 (0, dtheta) q).
bool CosseratRod::solve_constraints_direct(double h, RodContact* contact) {
  for (int j = 0; j < n_; ++j) {
    ss_lambda_[j].setZero();
    bt_lambda_[j].setZero();
  }
  direct_ran_ = true;  // for the contact hook's force queries below
  for (int it = 0; it < params_.iterations; ++it) {
    if (!direct_iteration(h)) return false;
    if (contact) contact->project(*this, it, h);
  }
  return true;
}

// one Newton iteration of the direct solve: the blocks assembled at the current iterate, the
// multipliers' change solved and applied
bool CosseratRod::direct_iteration(double h) {
  const double inv_h2 = 1.0 / (h * h);
  const double inv_l = 1.0 / l_, inv_l2 = inv_l * inv_l;
  const int f = hub_;  // segments before it are kinematic
  for (int j = f; j < n_; ++j) {
    const Eigen::Matrix3d r = q_[j].toRotationMatrix();
    const Eigen::Vector3d gamma = (x_[j + 1] - x_[j]) * inv_l - r.col(2);
    const Eigen::Matrix3d alpha_ss = r * (ss_compliance_[j] * inv_h2).asDiagonal() * r.transpose();
    const Eigen::Vector3d alpha_bt = bt_compliance_[j] * (inv_h2 / dual_length_m(j));
    Eigen::Vector3d omega;
    const Eigen::Matrix3d& c = ss_jacobian_[j] = stretch_shear_rotation_jacobian(q_[j]);
    const Eigen::Matrix3d& b = bt_jacobian_[j] =
        bend_twist_jacobian(pair_first_frame(j), q_[j], dual_length_m(j), rest_darboux_[j], &omega);
    const double wi = 4.0 * inv_inertia_q_[j];
    const double wi_prev = j > f ? 4.0 * inv_inertia_q_[j - 1] : 0.0;  // the hub's frame does not turn
    BlockTridiagonal6::Block& d = system_.diagonal(j);
    // (without springs the scalar inverse masses, as before the springs: the same operations)
    if (springs_in_solve_)
      d.topLeftCorner<3, 3>() =
          (node_inverse_mass(j) + node_inverse_mass(j + 1)) * inv_l2 + wi * c * c.transpose() + alpha_ss;
    else
      d.topLeftCorner<3, 3>() =
          (inv_mass_[j] + inv_mass_[j + 1]) * inv_l2 * Eigen::Matrix3d::Identity() + wi * c * c.transpose() + alpha_ss;
    d.topRightCorner<3, 3>() = wi * c * b.transpose();
    d.bottomLeftCorner<3, 3>() = d.topRightCorner<3, 3>().transpose();
    d.bottomRightCorner<3, 3>() = (wi_prev + wi) * b * b.transpose();
    d.bottomRightCorner<3, 3>().diagonal() += alpha_bt;
    rhs_[j].head<3>() = -(gamma + alpha_ss * ss_lambda_[j]);
    rhs_[j].tail<3>() = -(omega + alpha_bt.cwiseProduct(bt_lambda_[j]));
    if (j > f) {
      // segment j - 1 and j share node j (stretch-shear) and frame j - 1 (bend-twist j turns it by -B_j)
      BlockTridiagonal6::Block& u = system_.upper(j - 1);
      if (springs_in_solve_)
        u.topLeftCorner<3, 3>() = -node_inverse_mass(j) * inv_l2;
      else
        u.topLeftCorner<3, 3>() = -inv_mass_[j] * inv_l2 * Eigen::Matrix3d::Identity();
      u.topRightCorner<3, 3>() = -wi_prev * ss_jacobian_[j - 1] * b.transpose();
      u.bottomLeftCorner<3, 3>().setZero();
      u.bottomRightCorner<3, 3>() = -wi_prev * bt_jacobian_[j - 1] * b.transpose();
    }
  }
  if (!system_.factor(f)) return false;
  system_.solve(rhs_, &dlambda_, f);
  apply_multiplier_change();
  return true;
}

// Springs on nodes (a contact hook's wall and friction, issue #33), taken with the rod in one
// backward-Euler step: M (x - x~) = J^T lambda - h^2 K (x - a) gives
//   x = x^ + W J^T lambda,  W = (M + h^2 K)^-1,  x^ = W (M x~ + h^2 K a)
// so the solve above runs unchanged with W as the node's inverse mass, from x^. The hook may
// move the springs after a solve (a one-sided wall: on where the node ends inside, off where it
// would pull; friction's stiffness from the slip): the substep is then solved again from its
// prediction, up to the hook's say. (Newton on rod and springs together, each iteration
// continuing from the last with the springs moved, was tried: it blew the dead end up at the
// first bend, hub forces of hundreds of N)
bool CosseratRod::solve_with_springs(double h, RodContact* contact) {
  const int nodes = n_ + 1;
  // (round 0 may move nodes without velocity: before the prediction is kept)
  contact->place_springs(*this, 0, h);
  std::copy(x_.begin(), x_.end(), x_pred_.begin());
  std::copy(q_.begin(), q_.end(), q_pred_.begin());
  springs_in_solve_ = true;
  bool ok = true;
  for (int round = 1;; ++round) {
    for (int i = hub_ + 1; i < nodes; ++i) {
      if (!spring_on_[i]) continue;
      spring_w_[i] = (mass_[i] * Eigen::Matrix3d::Identity() + h * h * spring_k_[i]).inverse();
      x_[i] = spring_w_[i] * (mass_[i] * x_pred_[i] + h * h * (spring_k_[i] * spring_anchor_[i]));
    }
    ok = solve_constraints_direct(h, nullptr);
    if (!ok || !contact->place_springs(*this, round, h)) break;
    std::copy(x_pred_.begin(), x_pred_.end(), x_.begin());
    std::copy(q_pred_.begin(), q_pred_.end(), q_.begin());
  }
  springs_in_solve_ = false;
  if (!ok) {
    // the Gauss-Seidel fallback starts from the prediction
    std::copy(x_pred_.begin(), x_pred_.end(), x_.begin());
    std::copy(q_pred_.begin(), q_pred_.end(), q_.begin());
  }
  return ok;
}

// dx = W J^T dlambda, dtheta likewise, over the free units
void CosseratRod::apply_multiplier_change() {
  const int f = hub_;
  const double inv_l = 1.0 / l_;
  for (int j = f; j < n_; ++j) {
    ss_lambda_[j] += dlambda_[j].head<3>();
    bt_lambda_[j] += dlambda_[j].tail<3>();
  }
  for (int i = f + 1; i <= n_; ++i) {
    Eigen::Vector3d g = dlambda_[i - 1].head<3>();
    if (i < n_) g -= dlambda_[i].head<3>();
    if (springs_in_solve_ && spring_on_[i])
      x_[i] += spring_w_[i] * (inv_l * g);
    else
      x_[i] += inv_mass_[i] * inv_l * g;
  }
  for (int j = f; j < n_; ++j) {
    Eigen::Vector3d g =
        ss_jacobian_[j].transpose() * dlambda_[j].head<3>() + bt_jacobian_[j].transpose() * dlambda_[j].tail<3>();
    if (j + 1 < n_) g -= bt_jacobian_[j + 1].transpose() * dlambda_[j + 1].tail<3>();
    const Eigen::Vector3d dtheta = 4.0 * inv_inertia_q_[j] * g;
    const Eigen::Quaterniond w(0.0, dtheta.x(), dtheta.y(), dtheta.z());
    q_[j].coeffs() += 0.5 * (w * q_[j]).coeffs();
    q_[j].normalize();
  }
}

bool CosseratRod::contact_nodes_fit(std::span<const int> nodes) const {
  if (!direct_ran_ || params_.solver != RodSolver::kDirect) return false;
  int previous = hub_;
  for (int p : nodes) {
    if (p <= previous || p > n_) return false;
    previous = p;
  }
  return true;
}

// one column per node and axis: a unit impulse e on node p moves it by e / m_p directly
// (H W_z H^T) and pulls segments p - 1 and p, whose multipliers answer with
// y = -S^-1 J W_z H^T e; every listed node q then moves by W_z (J^T y)_q on top
bool CosseratRod::contact_compliance(std::span<const int> nodes, Eigen::Ref<Eigen::MatrixXd> w) {
  const int k = static_cast<int>(nodes.size());
  if (!contact_nodes_fit(nodes) || w.rows() != 3 * k || w.cols() != 3 * k) return false;
  if (k == 0) return true;
  const double inv_l = 1.0 / l_;
  // the three axes of node p at once; W is symmetric, so the column of node p is needed only for
  // the nodes from p on (their units from p - 1), and the rest is its mirror
  for (int a = 0; a < k; ++a) {
    const int p = nodes[a];
    const double s = inv_mass_[p] * inv_l;
    // node p ends segment p - 1 (J = I / l) and starts segment p (J = -I / l)
    column_rhs_[p - 1].topRows<3>() = -s * Eigen::Matrix3d::Identity();
    if (p < n_) column_rhs_[p].topRows<3>() = s * Eigen::Matrix3d::Identity();
    system_.solve_partial(column_rhs_, &column_, p - 1, p - 1);
    column_rhs_[p - 1].setZero();
    if (p < n_) column_rhs_[p].setZero();
    for (int b = a; b < k; ++b) {
      const int q = nodes[b];
      Eigen::Matrix3d g = column_[q - 1].topRows<3>();
      if (q < n_) g -= column_[q].topRows<3>();
      Eigen::Matrix3d dx = inv_mass_[q] * inv_l * g;
      if (q == p) dx.diagonal().array() += inv_mass_[p];
      w.block<3, 3>(3 * b, 3 * a) = dx;
      if (b != a) w.block<3, 3>(3 * a, 3 * b) = dx.transpose();
    }
  }
  return true;
}

bool CosseratRod::apply_contact_impulses(std::span<const int> nodes, std::span<const Eigen::Vector3d> impulses) {
  if (!contact_nodes_fit(nodes) || impulses.size() != nodes.size()) return false;
  if (nodes.empty()) return true;
  const int f = hub_;
  const double inv_l = 1.0 / l_;
  for (int j = f; j < n_; ++j) rhs_[j].setZero();
  for (size_t a = 0; a < nodes.size(); ++a) {
    const int p = nodes[a];
    const Eigen::Vector3d s = inv_mass_[p] * inv_l * impulses[a];
    rhs_[p - 1].head<3>() -= s;
    if (p < n_) rhs_[p].head<3>() += s;
  }
  system_.solve(rhs_, &dlambda_, f);
  apply_multiplier_change();
  for (size_t a = 0; a < nodes.size(); ++a) x_[nodes[a]] += inv_mass_[nodes[a]] * impulses[a];
  return true;
}

void CosseratRod::shift_node_without_velocity(int node, const Eigen::Vector3d& d_m) {
  if (node <= hub_ || node > n_) return;
  x_[node] += d_m;
  x_old_[node] += d_m;
}

// follow-the-leader length bound (Mueller et al. 2012): not a constraint of the paper, a
// safeguard. Without it the default wire (50 segments, 10 x 4) stretched a segment 2.5 times
// at 30 Hz under gravity and 300 times at 10 x the step.
void CosseratRod::guard_stretch() {
  const double g = params_.stretch_guard;
  if (g <= 0.0) return;
  const double lo = (1.0 - g) * l_, hi = (1.0 + g) * l_;
  for (int j = hub_; j < n_; ++j) {
    const Eigen::Vector3d d = x_[j + 1] - x_[j];
    const double len = d.norm();
    if (len > hi) {
      x_[j + 1] = x_[j] + (hi / len) * d;
    } else if (len < lo) {
      // a segment folded to nothing keeps its frame's direction
      const Eigen::Vector3d dir = len > 1e-12 * l_ ? Eigen::Vector3d(d / len) : q_[j] * Eigen::Vector3d::UnitZ();
      x_[j + 1] = x_[j] + lo * dir;
    }
  }
}

void CosseratRod::update_velocities(double h) {
  // implicit linear damping: a drag force m c v on the node's own mass, so a node heavier for
  // its motion (tip_mass_scale) takes its share of the rate, as it does of gravity
  for (int i = 0; i <= n_; ++i) {
    const double keep_i = 1.0 / (1.0 + node_damping_per_s(i) * h);
    v_[i] = (i <= hub_ ? 1.0 : keep_i) * (x_[i] - x_old_[i]) / h;
  }
  const double keep = 1.0 / (1.0 + params_.damping_per_s * h);  // (tip_mass_scale leaves the frames' inertia)
  for (int j = 0; j < n_; ++j) {
    Eigen::Quaterniond dq = q_old_[j].conjugate() * q_[j];
    if (dq.w() < 0.0) dq.coeffs() = -dq.coeffs();
    omega_[j] = keep * (2.0 / h) * dq.vec();
  }
}

void CosseratRod::save_state(RodState& s) const {
  s.x = x_;
  s.v = v_;
  s.omega = omega_;
  s.q = q_;
  s.clamp_q = clamp_q_;
  s.hub = hub_;
}

void CosseratRod::restore_state(const RodState& s) {
  if (s.x.size() != x_.size() || s.v.size() != v_.size() || s.omega.size() != omega_.size() || s.q.size() != q_.size())
    throw std::invalid_argument("rod: restore_state needs a state this rod saved");
  std::copy(s.x.begin(), s.x.end(), x_.begin());
  std::copy(s.v.begin(), s.v.end(), v_.begin());
  std::copy(s.omega.begin(), s.omega.end(), omega_.begin());
  std::copy(s.q.begin(), s.q.end(), q_.begin());
  clamp_q_ = s.clamp_q;
  set_hub_node(s.hub);  // the kinematic nodes' inverse masses with it
}

double CosseratRod::max_speed_m_per_s() const {
  double m = 0.0;
  for (const Eigen::Vector3d& v : v_) m = std::max(m, v.norm());
  return m;
}

bool CosseratRod::all_finite() const {
  for (const Eigen::Vector3d& p : x_)
    if (!p.allFinite()) return false;
  for (const Eigen::Quaterniond& q : q_)
    if (!q.coeffs().allFinite()) return false;
  for (const Eigen::Vector3d& v : v_)
    if (!v.allFinite()) return false;
  for (const Eigen::Vector3d& w : omega_)
    if (!w.allFinite()) return false;
  return true;
}

}  // namespace pcisim::physics::rod
