#include "physics/guidewire/wall_contact.h"

#include <algorithm>

namespace pcisim::physics {

WallContact::WallContact(const VesselContactParams& params, const LumenQuery& lumen, int node_count)
    : params_(params), lumen_(lumen) {
  touched_.assign(node_count, 0);
  normal_.assign(node_count, Eigen::Vector3d::UnitX());
  step_normal_.assign(node_count, Eigen::Vector3d::Zero());
  pass_normal_.assign(node_count, 0.0);
}

void WallContact::begin_step() {
  std::fill(touched_.begin(), touched_.end(), 0);
  std::fill(step_normal_.begin(), step_normal_.end(), Eigen::Vector3d::Zero());
  std::fill(pass_normal_.begin(), pass_normal_.end(), 0.0);
}

void WallContact::project(ChainMailWire& wire) {
  auto nodes = wire.mutable_nodes_m();
  const double eps = params_.wall_margin_m;
  std::fill(pass_normal_.begin(), pass_normal_.end(), 0.0);
  for (int i = wire.first_free_node(); i < wire.node_count(); ++i) {
    const WallSample s = lumen_.sample(nodes[i]);
    if (s.distance_m <= -eps) continue;
    // eq 15 prints p* = p + |eps - d| n with n pointing out of the lumen, which would push the
    // node further out; the sensible reading moves it inwards to depth eps: p* = p - (d + eps) n
    const Eigen::Vector3d dp = -(s.distance_m + eps) * s.normal;
    nodes[i] += dp;
    touched_[i] = 1;
    normal_[i] = s.normal;
    pass_normal_[i] = dp.norm();
    step_normal_[i] += dp;
  }
}

}  // namespace pcisim::physics
