#ifdef PCISIM_HAVE_CUDA
#include "xray/projectors/cuda_projector.h"

#include <stdexcept>

#include "xray/projectors/views.h"

namespace pcisim::xray {

bool CudaTrilinearProjector::available(std::string* why_not) {
  if (cuda::device_count() > 0) return true;
  if (why_not) *why_not = "no CUDA device is visible (cudaGetDeviceCount reports none)";
  return false;
}

CudaTrilinearProjector::CudaTrilinearProjector(const AttenuationVolume& volume, const TrilinearOptions& options)
    : volume_(volume) {
  std::string why;
  if (!available(&why)) throw std::runtime_error("CudaTrilinearProjector: " + why);
  grid_ = cuda::upload(grid_view(volume), volume.padded_count(), volume.brick_max().size());
  device_name_ = cuda::device_name();
  set_options(options);
}

CudaTrilinearProjector::~CudaTrilinearProjector() {
  cuda::release(&grid_);
  if (device_image_) cuda::free_image(device_image_);
}

void CudaTrilinearProjector::set_options(const TrilinearOptions& options) {
  if (!(options.step_voxels > 0)) throw std::invalid_argument("CudaTrilinearProjector: step_voxels must be > 0");
  if (options.slices && options.texture)
    throw std::invalid_argument("CudaTrilinearProjector: slices and texture are two ways to read mu; ask for one");
  // the texture's copy of mu only once a read through it is asked for
  if (options.texture && !grid_.texture) cuda::upload_texture(&grid_, grid_view(volume_));
  options_ = options;
}

float* CudaTrilinearProjector::image_for(const DetectorGeometry& g) {
  const size_t pixels = static_cast<size_t>(g.width) * g.height;
  if (pixels > device_pixels_) {  // only when the detector grows
    if (device_image_) cuda::free_image(device_image_);
    device_image_ = cuda::alloc_image(pixels);
    device_pixels_ = pixels;
  }
  return device_image_;
}

void CudaTrilinearProjector::project(const DetectorGeometry& g, Image* image) {
  if (image->width != g.width || image->height != g.height) {
    throw std::invalid_argument("CudaTrilinearProjector: image size differs from the detector's");
  }
  float* dev = image_for(g);
  cuda::render(grid_, detector_view(g), static_cast<float>(options_.step_voxels), options_.skip_empty, read(), dev);
  cuda::download(dev, image->pixels.data(), image->pixels.size());
}

std::vector<float> CudaTrilinearProjector::time_kernel_ms(const DetectorGeometry& g, int warmup, int runs) {
  return cuda::time_render(grid_, detector_view(g), static_cast<float>(options_.step_voxels), options_.skip_empty,
                           read(), image_for(g), warmup, runs);
}

}  // namespace pcisim::xray
#endif  // PCISIM_HAVE_CUDA
