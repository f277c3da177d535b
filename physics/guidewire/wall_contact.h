#pragma once
// Wire-wall contact (eq 15): a node closer to the wall than the margin epsilon, or outside the
// lumen, is moved back along the wall normal to depth epsilon. Records the normal corrections
// that friction (eqs 16-18) and the haptic force need.
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "physics/guidewire/chain_mail_wire.h"
#include "physics/guidewire/guidewire_params.h"
#include "physics/guidewire/lumen_query.h"

namespace pcisim::physics {

class WallContact {
 public:
  // `lumen` must outlive this object
  WallContact(const VesselContactParams& params, const LumenQuery& lumen, int node_count);

  void begin_step();                  // clears the per-step record
  void project(ChainMailWire& wire);  // one pass of eq 15 over the free nodes

  const VesselContactParams& params() const { return params_; }
  const LumenQuery& lumen() const { return lumen_; }
  std::span<const uint8_t> touched() const { return touched_; }        // in contact during this step
  std::span<const Eigen::Vector3d> normal() const { return normal_; }  // last wall normal
  // |delta p_n| of the last pass, and the correction vectors summed over the step
  std::span<const double> pass_normal_m() const { return pass_normal_; }
  std::span<const Eigen::Vector3d> step_normal_m() const { return step_normal_; }

 private:
  VesselContactParams params_;
  const LumenQuery& lumen_;
  std::vector<uint8_t> touched_;
  std::vector<Eigen::Vector3d> normal_, step_normal_;
  std::vector<double> pass_normal_;
};

}  // namespace pcisim::physics
