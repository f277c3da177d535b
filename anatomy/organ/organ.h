#pragma once
// An organ for the soft-tissue scene as plain data (issue #16): its closed surface, the fiducial
// beads inside it and the support it rests on. The case's CT (Case::ct) is the organ's CT.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "anatomy/mesh/triangle_mesh.h"

namespace pcisim::anatomy {

struct Organ {
  std::string name;
  TriangleMesh surface;                      // metres, closed, counter-clockwise seen from outside
  std::vector<Eigen::Vector3d> fiducials_m;  // bead centres
  // the support's top plane: free side where support_normal . x >= support_offset_m (normal unit,
  // pointing out of the support toward the organ)
  Eigen::Vector3d support_normal = -Eigen::Vector3d::UnitY();
  double support_offset_m = 0.0;
};

}  // namespace pcisim::anatomy
