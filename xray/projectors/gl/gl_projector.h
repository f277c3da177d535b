#pragma once
// The off-screen GL projector: the trilinear ray march of ray_march.h written as a fragment
// shader, run headless through OSMesa (Mesa's software GL). Its CPU twin is TrilinearProjector
// without empty-space skipping; a test compares the two. Built only with PCISIM_WITH_OSMESA.
#include <memory>
#include <string>

#include "xray/geometry/detector_geometry.h"
#include "xray/projectors/attenuation_volume.h"
#include "xray/projectors/image.h"

namespace pcisim::xray {

class GlProjector {
 public:
  // uploads the attenuation volume as a 3D texture; throws std::runtime_error with the reason
  // when no OpenGL 3.3 core context can be made
  GlProjector(const AttenuationVolume& volume, double step_voxels);
  ~GlProjector();

  // line integrals from the source to each pixel centre into image (already sized to g); the
  // GL context is made current on the calling thread
  void project(const DetectorGeometry& g, Image* image);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// whether this build has the GL projector and a context can be made; why not otherwise
bool gl_projector_available(std::string* why);

}  // namespace pcisim::xray
