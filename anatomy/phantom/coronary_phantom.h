#pragma once
// A procedural adult coronary tree (aortic root, LM, LAD, LCx, diagonals, marginals, RCA),
// seeded so that a scene names its anatomy with one number. Frame and dimensions: docs/anatomy.md.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::anatomy {

struct CoronaryPhantomSpec {
  uint32_t seed = 1;  // same seed, same tree (on every platform: no std distributions)
};

// branches in this order: aorta, LM, LAD, LCx, D1, D2, OM1, OM2, RCA; points every 0.5 mm.
// The frame is patient LPS (x left, y posterior, z superior) in metres, heart centre at origin.
VesselTree make_coronary_phantom(const CoronaryPhantomSpec& spec);

// the guide catheter's centerline, engaged in the LM: from the ascending aorta down to the LM's
// first point (which it ends on exactly), spaced ~0.5 mm, arriving along the LM's direction so
// the wire leaves the catheter straight into the LM. Empty if the tree has no aorta or LM.
std::vector<Eigen::Vector3d> guide_catheter_path(const VesselTree& tree);

}  // namespace pcisim::anatomy
