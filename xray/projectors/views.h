#pragma once
// Conversions from the Eigen-side types to the plain views the ray code reads.
#include "xray/geometry/detector_geometry.h"
#include "xray/projectors/attenuation_volume.h"
#include "xray/projectors/ray_march.h"

namespace pcisim::xray {

// mu and brick pointers are the host's; the CUDA projector swaps in device pointers
ray::GridView grid_view(const AttenuationVolume& volume);
ray::DetectorView detector_view(const DetectorGeometry& g);

}  // namespace pcisim::xray
