#pragma once
// Coulomb friction at the wall (eqs 16-18), static and kinetic, per wire section (body, tip).
// Works on displacements: the tangential motion of a touching node since the last friction pass
// is cancelled (static) or shortened by mu_k |delta p_n| (kinetic).
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "physics/guidewire/chain_mail_wire.h"
#include "physics/guidewire/guidewire_params.h"
#include "physics/guidewire/wall_contact.h"

namespace pcisim::physics {

class CoulombFriction {
 public:
  CoulombFriction(const FrictionParams& params, int node_count);

  void begin_step(const ChainMailWire& wire);  // motion is measured from the step start
  // after a contact pass
  void apply(ChainMailWire& wire, const WallContact& contact);

  const FrictionParams& params() const { return params_; }
  // last pass: tangential motion delta p_t, the friction correction, and the Coulomb bound used
  std::span<const Eigen::Vector3d> pass_tangential_m() const { return pass_tangential_; }
  std::span<const Eigen::Vector3d> pass_correction_m() const { return pass_correction_; }
  std::span<const double> pass_static_limit_m() const { return pass_static_limit_; }
  std::span<const Eigen::Vector3d> step_correction_m() const { return step_correction_; }
  // 1 where the last pass held a node by static friction
  std::span<const uint8_t> stuck() const { return stuck_; }

 private:
  FrictionParams params_;
  std::vector<Eigen::Vector3d> reference_;  // positions after the previous friction pass
  std::vector<Eigen::Vector3d> pass_tangential_, pass_correction_, step_correction_;
  std::vector<double> pass_static_limit_;
  std::vector<uint8_t> stuck_;
};

}  // namespace pcisim::physics
