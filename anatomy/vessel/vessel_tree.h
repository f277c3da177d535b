#pragma once
// A vessel tree as centerlines with radii: the one source of truth for the coronary anatomy.
// The lumen mesh, its SDF, the X-ray volume and the beating heart are all derived from it.
#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

namespace pcisim::anatomy {

struct CenterlinePoint {
  Eigen::Vector3d position_m;
  double radius_m = 0.0;
};

struct VesselBranch {
  std::string name;                     // "aorta", "LM", "LAD", "LCx", "RCA", "D1", "OM1", ...
  int parent = -1;                      // index into VesselTree::branches, -1 for the root
  int parent_point = -1;                // index of the parent's centerline point this branch leaves from
  std::vector<CenterlinePoint> points;  // ordered from proximal to distal
};

struct VesselTree {
  std::vector<VesselBranch> branches;

  // index of the branch with this name, or -1
  int find(std::string_view name) const;
};

// the branch whose centerline (as a polyline) is closest to p_m, or -1 for an empty tree.
// Brute force over segments, allocates nothing; meant for a few queries per step (the wire tip).
// Exact ties go to the lower index (a child's first point lies on its parent's centerline, so
// that point reports the parent). A NaN point returns -1 and an infinite distance.
int nearest_branch(const VesselTree& tree, const Eigen::Vector3d& p_m, double* distance_to_centerline_m = nullptr);

// the branch whose lumen holds p_m most deeply: the smallest (distance to its centerline minus the
// radius there), negative inside. Unlike nearest_branch, a point at the aorta's wall next to the
// left main's first points (which run inside the aorta) is in the aorta. -1 for an empty tree or
// a NaN point; `depth_m` gets that smallest value
int innermost_branch(const VesselTree& tree, const Eigen::Vector3d& p_m, double* depth_m = nullptr);

// arc length of a branch's centerline polyline
double branch_length_m(const VesselBranch& branch);

}  // namespace pcisim::anatomy
