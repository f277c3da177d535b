#pragma once
// The trilinear projector on the GPU (built when CUDA is found: PCISIM_HAVE_CUDA). The volume
// is uploaded once at construction (and once more as a 3-D texture when options.texture first
// asks for that read; the volume must outlive the projector); the device image is allocated once
// per detector size.
#ifdef PCISIM_HAVE_CUDA
#include <string>
#include <vector>

#include "xray/geometry/detector_geometry.h"
#include "xray/projectors/attenuation_volume.h"
#include "xray/projectors/cuda_trilinear.h"
#include "xray/projectors/image.h"
#include "xray/projectors/trilinear_projector.h"

namespace pcisim::xray {

class CudaTrilinearProjector {
 public:
  // true when a CUDA device is visible; otherwise why not
  static bool available(std::string* why_not = nullptr);

  // throws std::runtime_error when there is no device or the upload fails
  CudaTrilinearProjector(const AttenuationVolume& volume, const TrilinearOptions& options = {});
  ~CudaTrilinearProjector();
  CudaTrilinearProjector(const CudaTrilinearProjector&) = delete;
  CudaTrilinearProjector& operator=(const CudaTrilinearProjector&) = delete;

  void set_options(const TrilinearOptions& options);
  const TrilinearOptions& options() const { return options_; }
  std::string device_name() const { return device_name_; }

  // renders on the GPU and copies the line integrals into image (already sized to g)
  void project(const DetectorGeometry& g, Image* image);
  // kernel-only times (ms, CUDA events) of runs projections after warmup ones
  std::vector<float> time_kernel_ms(const DetectorGeometry& g, int warmup, int runs);

 private:
  float* image_for(const DetectorGeometry& g);
  cuda::Read read() const {
    return options_.slices ? cuda::Read::kSlices : options_.texture ? cuda::Read::kTexture : cuda::Read::kTwin;
  }

  const AttenuationVolume& volume_;  // for the texture, uploaded when options first ask for it
  TrilinearOptions options_;
  cuda::DeviceGrid grid_;
  float* device_image_ = nullptr;
  size_t device_pixels_ = 0;
  std::string device_name_;
};

}  // namespace pcisim::xray
#endif  // PCISIM_HAVE_CUDA
