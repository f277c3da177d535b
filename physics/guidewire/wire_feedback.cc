#include "physics/guidewire/wire_feedback.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace pcisim::physics {
namespace {

// unit wire direction at node i (distal), from its neighbours
Eigen::Vector3d tangent(std::span<const Eigen::Vector3d> x, int i) {
  const int a = std::max(i - 1, 0), b = std::min(i + 1, static_cast<int>(x.size()) - 1);
  const Eigen::Vector3d d = x[b] - x[a];
  const double n = d.norm();
  return n > 1e-12 ? Eigen::Vector3d(d / n) : Eigen::Vector3d::Zero();
}

// a 0.014-inch coronary wire
constexpr double kWireRadiusM = 0.178e-3;

}  // namespace

WireFeedback compute_feedback(const ChainMailWire& wire, const GuidewireParams& params, const WallContact* contact,
                              const CoulombFriction* friction) {
  WireFeedback f;
  const auto x = wire.nodes_m();
  const double k_wall = contact ? contact->params().wall_stiffness_n_per_m : 0.0;
  // eq 17 gives friction as a displacement; the wall's penalty stiffness turns it into newtons
  if (friction) {
    const auto c = friction->step_correction_m();
    double along = 0.0;
    for (int i = wire.first_free_node(); i < wire.node_count(); ++i) along -= c[i].dot(tangent(x, i));
    f.friction_n = k_wall * along;
  }
  // eq 20 reads k times the change of the first link's length since the last step. The change
  // that matters to the hand is the first link's compression against the instrument, i.e. the
  // feed the wire refused this step (commanded minus accepted insertion).
  const double refused = wire.commanded_feed_m() - wire.fed_length_m();
  f.internal_refused_feed_n = params.axial_stiffness_n_per_m * refused;
  // [guidewire eq 20] as written: F_internal = (|P1^t - P2^t| - |P1^(t-1) - P2^(t-1)|) k, P1 and P2
  // the first two chain-mails (here: the last node in the catheter and the first free one, the
  // link the hand pushes through). Sign: a link that shortened pushes back, resisting insertion
  // (positive), so F = -k (change of length) in our convention.
  const int p2 = wire.first_free_node();
  if (p2 >= 1 && p2 < wire.node_count()) {
    const auto now = wire.nodes_m();
    const auto before = wire.step_start_nodes_m();
    const double change_m = (now[p2] - now[p2 - 1]).norm() - (before[p2] - before[p2 - 1]).norm();
    f.internal_eq20_n = -params.axial_stiffness_n_per_m * change_m;
  }
  f.internal_n = params.internal_force == InternalForce::kEq20 ? f.internal_eq20_n : f.internal_refused_feed_n;
  if (refused > 1e-9) {
    f.stiffness_n_per_m = params.axial_stiffness_n_per_m;  // blocked: more push is refused 1:1
  } else if (contact) {
    // contacts facing along the wire resist insertion with the wall's penalty stiffness
    const auto n = contact->normal();
    const auto touched = contact->touched();
    double k = 0.0;
    for (int i = wire.first_free_node(); i < wire.node_count(); ++i) {
      if (touched[i]) k += k_wall * std::pow(n[i].dot(tangent(x, i)), 2);
    }
    f.stiffness_n_per_m = std::min(k, params.axial_stiffness_n_per_m);
  }
  // torque: wall friction on the wire's surface resists turning (mu_k N r per touching node).
  // The wire is torsionally stiff, so a tip stuck by static friction makes the free length
  // a torsion spring GJ / L against further turning.
  if (contact && friction) {
    const auto dn = contact->step_normal_m();
    const auto stuck = friction->stuck();
    const FrictionParams& fp = friction->params();
    double friction_torque = 0.0;
    for (int i = wire.first_free_node(); i < wire.node_count(); ++i) {
      const double mu = wire.node_in_tip(i) ? fp.tip_kinetic : fp.body_kinetic;
      friction_torque += mu * k_wall * dn[i].norm() * kWireRadiusM;
    }
    f.torque_nm = friction_torque;
    const int tip = wire.node_count() - 1;
    const double free_m = wire.fed_length_m();
    if (stuck[tip] && free_m > 1e-6) f.torsion_stiffness_nm_per_rad = params.torsional_rigidity_nm2 / free_m;
  }
  return f;
}

LocalForceModel to_local_force_model(const WireFeedback& f, const InstrumentInput& at, const GuidewireParams& params,
                                     double time_s, double step_s) {
  LocalForceModel m;
  m.made_utime = static_cast<int64_t>(std::llround(time_s * 1e6));
  m.valid_for_us = static_cast<int64_t>(std::llround(2.0 * step_s * 1e6));  // two physics periods
  m.x0_m = at.insertion_m;
  m.f0_n = f.friction_n + f.internal_n;  // eq 19
  m.k_n_per_m = std::max(f.stiffness_n_per_m, 0.0);
  m.b_n_s_per_m = params.axial_damping_n_s_per_m;
  m.q0_rad = at.rotation_rad;
  // friction resists the way the hand turns; at rest it holds nothing
  const double w = at.rotation_rate_rad_per_s;
  m.t0_nm = (w > 0.0 ? f.torque_nm : (w < 0.0 ? -f.torque_nm : 0.0)) + f.elastic_torque_nm;
  m.kt_nm_per_rad = std::max(f.torsion_stiffness_nm_per_rad, 0.0);
  m.bt_nm_s_per_rad = params.torsion_damping_nm_s_per_rad;
  if (!std::isfinite(m.f0_n) || !std::isfinite(m.k_n_per_m) || !std::isfinite(m.t0_nm) ||
      !std::isfinite(m.kt_nm_per_rad)) {
    m = LocalForceModel{};  // valid_for_us = 0: the haptic loop fades to zero
  }
  return m;
}

}  // namespace pcisim::physics
