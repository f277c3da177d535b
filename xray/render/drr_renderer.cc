#include "xray/render/drr_renderer.h"

#include <stdexcept>

#include "xray/projectors/siddon_projector.h"
#ifdef PCISIM_HAVE_CUDA
#include "xray/projectors/cuda_projector.h"
#endif
#ifdef PCISIM_HAVE_OSMESA
#include "xray/projectors/gl/gl_projector.h"
#endif

namespace pcisim::xray {

const char* projector_name(ProjectorKind kind) {
  switch (kind) {
    case ProjectorKind::kExact:
      return "exact";
    case ProjectorKind::kCpuTrilinear:
      return "cpu";
    case ProjectorKind::kCudaTrilinear:
      return "cuda";
    case ProjectorKind::kGl:
      return "gl";
  }
  return "?";
}

struct DrrRenderer::Impl {
  std::unique_ptr<SiddonProjector> exact;
  std::unique_ptr<TrilinearProjector> cpu;
#ifdef PCISIM_HAVE_CUDA
  std::unique_ptr<CudaTrilinearProjector> cuda;
#endif
#ifdef PCISIM_HAVE_OSMESA
  std::unique_ptr<GlProjector> gl;
#endif
};

DrrRenderer::DrrRenderer(const anatomy::Volume& volume, const DrrRendererOptions& options)
    : options_(options),
      attenuation_(std::make_unique<AttenuationVolume>(volume, options.attenuation)),
      impl_(std::make_unique<Impl>()) {
  switch (options.projector) {
    case ProjectorKind::kExact:
      impl_->exact = std::make_unique<SiddonProjector>(*attenuation_, options.trilinear.threads);
      break;
    case ProjectorKind::kCpuTrilinear:
      impl_->cpu = std::make_unique<TrilinearProjector>(*attenuation_, options.trilinear);
      break;
    case ProjectorKind::kCudaTrilinear:
#ifdef PCISIM_HAVE_CUDA
      impl_->cuda = std::make_unique<CudaTrilinearProjector>(*attenuation_, options.trilinear);
      break;
#else
      throw std::runtime_error("DrrRenderer: the cuda projector needs a build with CUDA");
#endif
    case ProjectorKind::kGl:
#ifdef PCISIM_HAVE_OSMESA
      impl_->gl = std::make_unique<GlProjector>(*attenuation_, options.trilinear.step_voxels);
      break;
#else
      throw std::runtime_error("DrrRenderer: the gl projector needs a build with OSMesa");
#endif
  }
}

DrrRenderer::~DrrRenderer() = default;

void DrrRenderer::render(const DetectorGeometry& g, Image* image) {
  if (image->width != g.width || image->height != g.height) image->resize(g.width, g.height);
  if (impl_->exact) {
    impl_->exact->project(g, image);
  } else if (impl_->cpu) {
    impl_->cpu->project(g, image);
  }
#ifdef PCISIM_HAVE_CUDA
  else if (impl_->cuda) {
    impl_->cuda->project(g, image);
  }
#endif
#ifdef PCISIM_HAVE_OSMESA
  else if (impl_->gl) {
    impl_->gl->project(g, image);
  }
#endif
}

}  // namespace pcisim::xray
