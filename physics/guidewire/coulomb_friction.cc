#include "physics/guidewire/coulomb_friction.h"

#include <algorithm>

namespace pcisim::physics {

CoulombFriction::CoulombFriction(const FrictionParams& params, int node_count) : params_(params) {
  reference_.assign(node_count, Eigen::Vector3d::Zero());
  pass_tangential_.assign(node_count, Eigen::Vector3d::Zero());
  pass_correction_.assign(node_count, Eigen::Vector3d::Zero());
  step_correction_.assign(node_count, Eigen::Vector3d::Zero());
  pass_static_limit_.assign(node_count, 0.0);
  stuck_.assign(node_count, 0);
}

void CoulombFriction::begin_step(const ChainMailWire& wire) {
  const auto start = wire.step_start_nodes_m();
  std::copy(start.begin(), start.end(), reference_.begin());
  std::fill(step_correction_.begin(), step_correction_.end(), Eigen::Vector3d::Zero());
}

void CoulombFriction::apply(ChainMailWire& wire, const WallContact& contact) {
  auto nodes = wire.mutable_nodes_m();
  std::fill(pass_tangential_.begin(), pass_tangential_.end(), Eigen::Vector3d::Zero());
  std::fill(pass_correction_.begin(), pass_correction_.end(), Eigen::Vector3d::Zero());
  std::fill(pass_static_limit_.begin(), pass_static_limit_.end(), 0.0);
  std::fill(stuck_.begin(), stuck_.end(), 0);
  const auto dn_len = contact.pass_normal_m();
  const auto normal = contact.normal();
  for (int i = wire.first_free_node(); i < wire.node_count(); ++i) {
    const double dn = dn_len[i];
    if (dn <= 0.0) continue;
    const bool tip = wire.node_in_tip(i);
    const double mu_s = tip ? params_.tip_static : params_.body_static;
    const double mu_k = tip ? params_.tip_kinetic : params_.body_kinetic;
    // eq 16: split the motion into normal and tangential parts; the normal part was answered by
    // the wall, friction acts on the tangential part
    const Eigen::Vector3d& n = normal[i];
    const Eigen::Vector3d d = nodes[i] - reference_[i];
    const Eigen::Vector3d dt = d - n * d.dot(n);
    const double dt_len = dt.norm();
    Eigen::Vector3d c;
    if (dt_len <= mu_s * dn) {
      c = -dt;  // static: the node sticks
      stuck_[i] = 1;
    } else {
      // eqs 17-18: beta is the fraction of tangential motion left, in [0, 1]. The printed
      // beta = -max(...) has a stray sign (it would make beta <= 0 and friction push forward)
      const double beta = std::max((dt_len - mu_k * dn) / dt_len, 0.0);
      c = (beta - 1.0) * dt;
    }
    nodes[i] += c;
    pass_tangential_[i] = dt;
    pass_correction_[i] = c;
    pass_static_limit_[i] = mu_s * dn;
    step_correction_[i] += c;
  }
  std::copy(nodes.begin(), nodes.end(), reference_.begin());
}

}  // namespace pcisim::physics
