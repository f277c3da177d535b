#pragma once
// Tubes for the wire's mechanics rigs (issue #33): one-branch vessel trees whose lumen is the
// union of capsules along a centerline (physics::TubeLumen), so the far end is closed by a
// hemispherical cap. The one source of the rod tests' bent tube and of the wire-force bench's.
#include <Eigen/Core>
#include <vector>

#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::anatomy {

// one branch through the given centerline points, one lumen radius throughout
VesselTree tube_through(const std::vector<Eigen::Vector3d>& centerline_m, double lumen_radius_m);

// the bent tube: from the origin 40 mm straight along +z, then a 90 degree bend of 15 mm radius
// towards +x, then 60 mm straight along +x (closed 124 mm along its centerline); 1.5 mm lumen
// radius
VesselTree bent_tube_phantom();

}  // namespace pcisim::anatomy
