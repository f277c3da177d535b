#pragma once
// Attenuation of a tube (wire, iodine-filled lumen) added to a line-integral image analytically:
// mu x the closed-form chord of each pixel's ray through each segment's truncated cone, visiting
// only the pixels of the segment's projected bounding box. Never voxelised, allocates nothing.
#include <Eigen/Core>
#include <array>

#include "xray/geometry/detector_geometry.h"
#include "xray/projectors/image.h"

namespace pcisim::xray {

// the pixels add_cone_segment visits for that cone: columns [box[0], box[1]], rows [box[2], box[3]]
// (both included); false when its shadow misses the detector or an end is behind the source
bool cone_shadow_box(const DetectorGeometry& g, const Eigen::Vector3d& a_mm, const Eigen::Vector3d& b_mm, double ra_mm,
                     double rb_mm, std::array<int, 4>* box);

// adds mu_per_mm x chord through the cone from a (radius ra_mm) to b (radius rb_mm) to every
// pixel whose ray (source -> pixel centre) crosses it; segments behind the source are skipped
void add_cone_segment(const DetectorGeometry& g, const Eigen::Vector3d& a_mm, const Eigen::Vector3d& b_mm, double ra_mm,
                      double rb_mm, double mu_per_mm, Image* image);

}  // namespace pcisim::xray
