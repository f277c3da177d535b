#pragma once
// An immutable copy of what other threads may look at after a physics step.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace pcisim::physics {

struct WorldSnapshot {
  double time_s = 0.0;
  int64_t step = 0;
  std::vector<Eigen::Vector3d> wire_nodes_m;  // proximal to distal; empty without guidewire
  std::vector<uint8_t> wire_contact;          // 1 where a node touches the wall
  // the wall's force on each node over the step, N, world axes: the rod's (normal and friction
  // with its wall in the solve, the normal alone with the projection); zero for the chain-mail,
  // whose wall is a projection with no load response (docs/guidewire.md)
  std::vector<Eigen::Vector3d> wire_contact_force_n;
  double tip_force_n = 0.0;  // the wall's normal force summed over the tip's nodes (the rod; 0 for the chain-mail)
  // what the wire pushes back on the hub with, along the feed (+ resists insertion) and about it
  // (+ resists positive rotation): the rod's clamp multipliers, the chain-mail's [guidewire eq 19]
  double hub_force_n = 0.0, hub_torque_nm = 0.0;
  Eigen::Vector3d tip_m = Eigen::Vector3d::Zero();
  // the tip in the vessels' rest frame (the heart's motion taken out): where the trainee steered it
  Eigen::Vector3d tip_rest_m = Eigen::Vector3d::Zero();
  int tip_branch = -1;       // index into the vessel tree, -1 when unknown
  double insertion_m = 0.0;  // insertion the step used
  double rotation_rad = 0.0;
  double heart_phase = 0.0;  // [0, 1) of the cardiac cycle; 0 without heart_beat
  // the coronary centerline points where the heart has carried them, in tree order (branch 0's
  // points, then branch 1's, ...); empty without vessel_motion (the tree is at rest)
  std::vector<Eigen::Vector3d> vessel_points_m;

  // the soft-tissue scene (empty / zero without soft_tissue): the coarse tet mesh's vertices and
  // the fiducials where the tissue has carried them (same order as at rest)
  std::vector<Eigen::Vector3d> tissue_tet_vertices_m;
  std::vector<Eigen::Vector3d> fiducials_m;
  // the probe as the step left it (probe_contact): face centre, rotation probe -> scene (columns:
  // lateral, elevation, beam), the force the tissue puts on it, and the imaging asked for
  bool probe_present = false;
  Eigen::Vector3d probe_position_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d probe_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d probe_force_n = Eigen::Vector3d::Zero();
  double probe_depth_mm = 0.0, probe_gain_db = 0.0;
};

}  // namespace pcisim::physics
