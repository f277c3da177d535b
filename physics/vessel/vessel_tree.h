#pragma once
// A vessel tree as centerlines with radii: the one source of truth for the coronary anatomy.
// The lumen mesh, its SDF, the X-ray volume and the beating heart are all derived from it.
#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

namespace pcisim::physics {

struct CenterlinePoint {
  Eigen::Vector3d position_m;
  double radius_m = 0.0;
};

struct VesselBranch {
  std::string name;            // "aorta", "LM", "LAD", "LCx", "RCA", "D1", "OM1", ...
  int parent = -1;             // index into VesselTree::branches, -1 for the root
  int parent_point = -1;       // index of the parent's centerline point this branch leaves from
  std::vector<CenterlinePoint> points;  // ordered from proximal to distal
};

struct VesselTree {
  std::vector<VesselBranch> branches;

  // index of the branch with this name, or -1
  int find(std::string_view name) const;
};

}  // namespace pcisim::physics
