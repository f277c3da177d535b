#pragma once
// The CT the fluoroscopy projects as its background, from a case: the case's CT when it has one
// (its lumens refilled with blood when it is a CT angiogram: the iodine comes per frame, from the
// bolus model), else the procedural thorax built around the case's vessel tree.
#include "anatomy/case/case.h"
#include "anatomy/volume/volume.h"
#include "xray/fluoro/fluoroscopy.h"

namespace pcisim::xray {

anatomy::Volume background_volume(const anatomy::Case& c, const FluoroSpec& spec);

// the procedural thorax around `tree` at the spec's background resolution, lumens blood-filled
anatomy::Volume thorax_background(const anatomy::VesselTree& tree, const FluoroSpec& spec);

// every voxel whose centre lies inside a branch's tube (centerline +- radius) and is brighter
// than blood is set to blood_hu; returns how many voxels changed
int64_t fill_lumens_with_blood(anatomy::Volume& ct, const anatomy::VesselTree& tree, double blood_hu);

}  // namespace pcisim::xray
