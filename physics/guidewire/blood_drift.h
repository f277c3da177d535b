#pragma once
// Blood flow acting on the wire through virtual wire-blood links (eq 12): each free node drifts
// with a fraction of the local flow velocity. The flow is steady, along the nearest centerline,
// precomputed on a coarse grid so a step only interpolates.
#include <Eigen/Core>
#include <vector>

#include "physics/guidewire/chain_mail_wire.h"
#include "physics/guidewire/guidewire_params.h"
#include "physics/vessel/vessel_tree.h"

namespace pcisim::physics {

class BloodDrift {
 public:
  BloodDrift(const BloodFlowParams& params, const VesselTree& tree, double grid_m = 1e-3);

  // flow velocity at p (m/s); zero away from the vessels. Allocates nothing.
  Eigen::Vector3d velocity(const Eigen::Vector3d& p_m) const;
  void apply(ChainMailWire& wire, double dt_s) const;

  const BloodFlowParams& params() const { return params_; }

 private:
  BloodFlowParams params_;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  double grid_m_ = 1e-3;
  std::vector<Eigen::Vector3f> velocity_;  // x fastest
};

}  // namespace pcisim::physics
