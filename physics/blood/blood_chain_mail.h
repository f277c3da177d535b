#pragma once
// Blood as chain-mails (chain-mail paper, section IV.A): along every coronary centerline a column
// of blood chain-mails, one on the axis and a ring around it, each carried by the vessel through
// a virtual vessel-blood link (eq 11) and flowing downstream with a pulsatile velocity: the flow
// rate follows the cardiac cycle and the velocity across the lumen is parabolic (Poiseuille).
// The wire's free nodes are moved by the blood chain-mails near them through weighted virtual
// links (eq 12).
//
// Frame: the vessels' rest (material) frame, in which the wire is simulated (docs/heart.md);
// eq 11 is then the identity here, and VesselSkin carries both into the world frame.
// Built once; step() and apply() allocate nothing.
#include <Eigen/Core>
#include <span>
#include <vector>

#include "physics/guidewire/chain_mail_wire.h"
#include "physics/guidewire/guidewire_params.h"
#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::physics {

// the flow rate over one cycle as a fraction of its mean (mean 1): 1 - pulsatility through
// systole (the first kSystoleFraction of the cycle), a diastolic hump after it
double coronary_flow_fraction(double phase, double pulsatility);
inline constexpr double kSystoleFraction = 0.35;

// throws std::invalid_argument naming the field ("blood_flow.cell_spacing_m: ...") when out of range
void validate(const BloodFlowParams& params);

class BloodChainMail {
 public:
  // throws like validate()
  BloodChainMail(const BloodFlowParams& params, const anatomy::VesselTree& rest_tree);

  // advances every blood chain-mail downstream by its velocity at this cardiac phase; cells that
  // leave a branch's distal end re-enter at its proximal end
  void step(double dt_s, double phase);
  // eq 12 on the wire's free nodes: q* = q + gain * sum_i w_i v_i dt, w_i ~ 1 / d_i
  void apply(ChainMailWire& wire, double dt_s) const;
  // the same drift on any wire's nodes from first_free on (the rod model)
  void apply(std::span<Eigen::Vector3d> nodes_m, int first_free, double dt_s) const;

  // the blended blood velocity a point would take (eq 12's sum), m/s; zero away from the blood
  Eigen::Vector3d linked_velocity(const Eigen::Vector3d& p_m) const;

  int cell_count() const { return static_cast<int>(pos_.size()); }
  std::span<const Eigen::Vector3d> cell_positions_m() const { return pos_; }
  std::span<const Eigen::Vector3d> cell_velocities_m_per_s() const { return vel_; }
  const BloodFlowParams& params() const { return params_; }

 private:
  struct Branch {
    int first_point = 0, point_count = 0;  // into the flattened centerline below
    double length_m = 0.0;
  };
  struct Cell {
    int branch = 0;
    double s_m = 0.0;              // arc length along the branch
    double ring_angle = 0.0;       // around the axis
    double radial_fraction = 0.0;  // of the local radius: 0 on the axis
  };
  void place(int c);                             // position and velocity of cell c from its s
  double speed_m_per_s(const Cell& cell) const;  // at the current flow rate
  void rebuild_hash();

  BloodFlowParams params_;
  double flow_fraction_ = 1.0;
  std::vector<Branch> branches_;
  std::vector<Eigen::Vector3d> point_m_, tangent_, normal_;
  std::vector<double> radius_m_, arc_m_;
  std::vector<Cell> cells_;
  std::vector<Eigen::Vector3d> pos_, vel_;
  // spatial hash: bucket -> [bucket_start_[b], bucket_start_[b + 1]) in bucket_cells_
  std::vector<int> bucket_start_, bucket_fill_, bucket_cells_, cell_bucket_;
};

}  // namespace pcisim::physics
