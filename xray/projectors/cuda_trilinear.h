#pragma once
// The CUDA side of the trilinear projector, behind a plain interface (no Eigen, no CUDA types)
// so that only cuda_trilinear.cu needs nvcc. Every function throws std::runtime_error naming the
// CUDA call and its error string when CUDA fails.
#include <cstddef>
#include <string>
#include <vector>

#include "xray/projectors/ray_march.h"

namespace pcisim::xray::cuda {

// visible CUDA devices; 0 when there is no GPU or no driver (never throws)
int device_count();
// "NVIDIA H100 80GB HBM3 (sm_90)" for device 0
std::string device_name();

struct DeviceGrid {
  float* mu = nullptr;
  float* brick_max = nullptr;
  ray::GridView view;  // device pointers
  // the same padded mu as a 3-D texture with the hardware's trilinear filtering (a
  // cudaTextureObject_t and its cudaArray_t, kept as plain integers here: no CUDA types)
  unsigned long long texture = 0;
  void* texture_array = nullptr;
};

// copies the padded mu and the brick maxima of a host view to device 0
DeviceGrid upload(const ray::GridView& host, size_t mu_count, size_t brick_count);
// and mu into a 3-D texture too (a second copy on the device), for Read::kTexture
void upload_texture(DeviceGrid* grid, const ray::GridView& host);
void release(DeviceGrid* grid);

float* alloc_image(size_t pixels);
void free_image(float* image);

// how a projection reads mu: ray::trilinear on global memory (the CPU marcher's twin), the
// texture unit's trilinear filter (its weights have 8 fractional bits: not the twin; the grid
// must have been uploaded with its texture), or Joseph's method, ray::slice_ray (the twin of the
// CPU's TrilinearOptions::slices; step_voxels unused)
enum class Read { kTwin, kTexture, kSlices };

// launches the projection of d into image (device, width x height) and waits for it
void render(const DeviceGrid& grid, const ray::DetectorView& d, float step_voxels, bool skip_empty, Read read,
            float* image);
void download(const float* device_image, float* host, size_t pixels);

// kernel times (ms, CUDA events around each launch) of runs launches after warmup launches
std::vector<float> time_render(const DeviceGrid& grid, const ray::DetectorView& d, float step_voxels, bool skip_empty,
                               Read read, float* image, int warmup, int runs);

}  // namespace pcisim::xray::cuda
