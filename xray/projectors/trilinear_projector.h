#pragma once
// The fast CPU projector: trilinear interpolation of mu sampled every step_voxels along each
// ray (midpoint rule), empty bricks skipped, rows spread over a thread pool, eight rays of a row
// at a time with AVX2. The CUDA projector
// runs the same ray code (ray_march.h) and is compared with this one.
#include "xray/geometry/detector_geometry.h"
#include "xray/projectors/attenuation_volume.h"
#include "xray/projectors/image.h"
#include "realtime/row_pool.h"

namespace pcisim::xray {

// the step a scene may ask for: time grows as 1/step, and below a quarter voxel the image no
// longer changes visibly (docs/benchmarks/xray.md); 0.05 once turned a 0.5 s run into 22 s
inline constexpr double kMinSceneStepVoxels = 0.25, kMaxSceneStepVoxels = 4.0;

struct TrilinearOptions {
  double step_voxels = 0.5;  // sample spacing along the ray, in voxels
  bool skip_empty = true;    // walk the brick grid and skip bricks without mu
  int threads = 0;           // CPU only; <= 0: all cores
  // CPU only: eight neighbouring rays at once with AVX2 where the CPU has it (ray_packet.h),
  // the same samples to the last bits; false: one ray at a time (ray::trilinear_ray)
  bool packets = true;
  // CUDA only: read mu through the texture unit's trilinear filter (8 fractional bits in its
  // weights: not the CPU marcher's twin; issue #36 item 4) instead of ray::trilinear
  bool texture = false;
  // sample where each ray crosses the voxel planes of its major axis, mu bilinear in the plane
  // (Joseph's method, ray::slice_ray, the CUDA kernel's too): 4 reads a sample instead of 8, and
  // one sample per plane; step_voxels is then unused (issue #36 item 3: docs/xray.md)
  bool slices = false;
};

class TrilinearProjector {
 public:
  // keeps a reference to volume
  TrilinearProjector(const AttenuationVolume& volume, const TrilinearOptions& options = {});

  void set_options(const TrilinearOptions& options);  // threads are fixed at construction
  const TrilinearOptions& options() const { return options_; }

  // line integrals from the source to each pixel centre into image (already sized to g)
  void project(const DetectorGeometry& g, Image* image) { project(volume_, g, image); }
  // the same through another volume on this projector's threads (the beating background's
  // per-phase differences)
  void project(const AttenuationVolume& volume, const DetectorGeometry& g, Image* image);

 private:
  const AttenuationVolume& volume_;
  TrilinearOptions options_;
  realtime::RowPool pool_;
};

}  // namespace pcisim::xray
