#pragma once
// The reference projector: exact line integrals through the piecewise-constant (nearest-voxel)
// volume by incremental voxel traversal (Siddon 1985, Med. Phys. 12:252; Jacobs et al. 1998,
// "A fast algorithm to calculate the exact radiological path through a pixel or voxel space"),
// in double precision, rows spread over a thread pool.
#include <Eigen/Core>

#include "xray/geometry/detector_geometry.h"
#include "xray/projectors/attenuation_volume.h"
#include "xray/projectors/image.h"
#include "xray/projectors/row_pool.h"

namespace pcisim::xray {

// exact integral of mu along the segment a_mm -> b_mm (1/mm x mm)
double exact_line_integral(const AttenuationVolume& volume, const Eigen::Vector3d& a_mm, const Eigen::Vector3d& b_mm);

class SiddonProjector {
 public:
  // keeps a reference to volume; threads <= 0: all cores
  explicit SiddonProjector(const AttenuationVolume& volume, int threads = 0);

  // line integrals from the source to each pixel centre into image (already sized to g)
  void project(const DetectorGeometry& g, Image* image);

 private:
  const AttenuationVolume& volume_;
  RowPool pool_;
};

}  // namespace pcisim::xray
