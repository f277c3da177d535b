#pragma once
// The one object the x-ray thread needs: a CT volume turned into attenuation once, a projector
// chosen once, and a render call per frame into a caller-owned image (nothing allocated per frame
// once the image has its size). C-arm poses go through c_arm_geometry().
#include <memory>
#include <string>

#include "xray/geometry/c_arm.h"
#include "xray/geometry/detector_geometry.h"
#include "xray/projectors/attenuation_volume.h"
#include "xray/projectors/image.h"
#include "xray/projectors/trilinear_projector.h"
#include "anatomy/volume/volume.h"

namespace pcisim::xray {

enum class ProjectorKind { kExact, kCpuTrilinear, kCudaTrilinear, kGl };

// "exact", "cpu", "cuda", "gl"
const char* projector_name(ProjectorKind kind);

struct DrrRendererOptions {
  ProjectorKind projector = ProjectorKind::kCpuTrilinear;
  TrilinearOptions trilinear;     // step, empty-space skipping, CPU threads (exact uses threads too)
  AttenuationParams attenuation;  // mu_water, air threshold, brick size
};

class DrrRenderer {
 public:
  // builds the attenuation volume (and uploads it for CUDA); throws std::runtime_error when the
  // CUDA projector is asked for and no GPU is there (or the build has no CUDA)
  DrrRenderer(const anatomy::Volume& volume, const DrrRendererOptions& options = {});
  ~DrrRenderer();

  // line integrals for the detector g into image, resized only when g's size differs
  void render(const DetectorGeometry& g, Image* image);
  void render(const CArmSpec& spec, const CArmPose& pose, Image* image) { render(c_arm_geometry(spec, pose), image); }

  const AttenuationVolume& attenuation() const { return *attenuation_; }
  ProjectorKind projector() const { return options_.projector; }

 private:
  struct Impl;
  DrrRendererOptions options_;
  std::unique_ptr<AttenuationVolume> attenuation_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pcisim::xray
