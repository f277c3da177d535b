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
  Eigen::Vector3d tip_m = Eigen::Vector3d::Zero();
  int tip_branch = -1;       // index into the vessel tree, -1 when unknown
  double insertion_m = 0.0;  // insertion the step used
  double rotation_rad = 0.0;
  double heart_phase = 0.0;  // [0, 1) of the cardiac cycle; 0 without heart_beat
  // the coronary centerline points where the heart has carried them, in tree order (branch 0's
  // points, then branch 1's, ...); empty without vessel_motion (the tree is at rest)
  std::vector<Eigen::Vector3d> vessel_points_m;
};

}  // namespace pcisim::physics
