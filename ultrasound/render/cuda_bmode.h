#pragma once
// The B-mode renderer's passes on the GPU (built when CUDA is found: PCISIM_HAVE_CUDA): the
// rules of bmode_kernels.h, one thread a scanline for the march and the echo's running products,
// one a sample or pixel for the rest (scatterers, the echo's other rules, the PSF, compression,
// scan conversion). Behind a plain interface (no CUDA
// types) so that only cuda_bmode.cu needs nvcc; BModeRenderer owns one when its settings ask for
// the cuda renderer. Every call throws std::runtime_error naming the CUDA call and its error
// string when CUDA fails.
#include <cstddef>
#include <cstdint>
#include <string>

#include "ultrasound/render/bmode_kernels.h"

namespace pcisim::ultrasound::cuda {

// visible CUDA devices; 0 when there is no GPU or no driver (never throws)
int device_count();
// "NVIDIA H200 (sm_90)" for device 0
std::string device_name();

class BModeDevice {
 public:
  // copies the tissue map (labels, voxels of them, and label_count tissues' properties) and the
  // scatterers' table to device 0, and allocates a width x height frame's arrays there
  BModeDevice(const kernels::LabelView& labels, int64_t voxels, int label_count, int width, int height);
  ~BModeDevice();
  BModeDevice(const BModeDevice&) = delete;
  BModeDevice& operator=(const BModeDevice&) = delete;

  // what changes only with the depth: the scanlines, the kernels, the scan conversion (host's arrays)
  void upload_geometry(const kernels::FrameView& host, bool curved);
  // page-locks host memory the frames are copied into (the copies then go straight to it, about
  // twice as fast); undone by the destructor, which must run before that memory is freed
  void pin(void* host, size_t bytes);
  // the tets' rest arrays (after TetLocator::build)
  void upload_rest(const LocatorView& host);
  // one frame: the tets' current arrays (cells + 1 starts, entries entries; the device's room for
  // them grows to entries_capacity, the host's reserve, so frames allocate no more than the host
  // does) when locator is given, the passes, and the beam-space grey levels and (curved) the
  // display image copied back into host's arrays; the scalars (gain, TGC...) are host's
  void render(const kernels::FrameView& host, const kernels::PoseView& pose, const LocatorView* locator, int cells,
              int entries, long entries_capacity, uint64_t mixed_seed, bool curved);
  // the last frame's echo intensity (width x height floats) into host
  void download_echo(float* host) const;
  // the last render()'s passes on the GPU (ms, CUDA events: the kernels, no copies), in all and
  // each pass's (march, echo, axial PSF, lateral PSF, scan conversion)
  static constexpr int kPasses = 5;
  float last_kernel_ms() const { return last_kernel_ms_; }
  const float* last_pass_ms() const { return last_pass_ms_; }

 private:
  struct Buffers;
  Buffers* b_;
  float last_kernel_ms_ = 0.0f;
  float last_pass_ms_[kPasses] = {};
};

}  // namespace pcisim::ultrasound::cuda
