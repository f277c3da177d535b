// CUDA twin of the CPU trilinear marcher: one thread per detector pixel running the same
// ray::trilinear_ray as TrilinearProjector; or the same rays and samples read through the texture
// unit's trilinear filter (issue #36 item 4: not the twin, its weights have 8 fractional bits).
#include <cuda_runtime.h>

#include <stdexcept>
#include <string>

#include "xray/projectors/cuda_trilinear.h"

namespace pcisim::xray::cuda {
namespace {

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw std::runtime_error(std::string("CUDA ") + what + ": " + cudaGetErrorString(e));
}

__global__ void project_kernel(ray::GridView g, ray::DetectorView d, float step, bool skip, float* image) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  const int r = blockIdx.y * blockDim.y + threadIdx.y;
  if (c >= d.width || r >= d.height) return;
  image[static_cast<size_t>(r) * d.width + c] = ray::trilinear_ray(g, d, c, r, step, skip);
}

// Joseph's method: the CPU's ray::slice_ray, one thread a pixel
__global__ void project_slices_kernel(ray::GridView g, ray::DetectorView d, bool skip, float* image) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  const int r = blockIdx.y * blockDim.y + threadIdx.y;
  if (c >= d.width || r >= d.height) return;
  image[static_cast<size_t>(r) * d.width + c] = ray::slice_ray(g, d, c, r, skip);
}

// the same ray (setup_ray, for_each_run: the same samples), each sample read by the texture
// unit: padded voxel centres at integers are texel centres at +0.5; outside reads the border, 0
__global__ void project_texture_kernel(ray::GridView g, cudaTextureObject_t mu, ray::DetectorView d, float step,
                                       bool skip, float* image) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  const int r = blockIdx.y * blockDim.y + threadIdx.y;
  if (c >= d.width || r >= d.height) return;
  ray::RaySetup s;
  float acc = 0.f;
  if (ray::setup_ray(g, d, c, r, step, &s)) {
    auto run = [&](int lo, int hi) {
      for (int k = lo; k < hi; ++k) {
        const float t = s.t0 + (k + 0.5f) * s.dt;
        acc +=
            tex3D<float>(mu, s.x0[0] + t * s.dx[0] + 0.5f, s.x0[1] + t * s.dx[1] + 0.5f, s.x0[2] + t * s.dx[2] + 0.5f);
      }
    };
    ray::for_each_run(g, s, skip, run);
    acc *= s.dt * s.len_mm;
  }
  image[static_cast<size_t>(r) * d.width + c] = acc;
}

void launch(const DeviceGrid& grid, const ray::DetectorView& d, float step, bool skip, Read read, float* image) {
  const dim3 block(16, 8);
  const dim3 blocks((d.width + block.x - 1) / block.x, (d.height + block.y - 1) / block.y);
  if (read == Read::kTexture) {
    if (!grid.texture) throw std::runtime_error("CUDA projection: the grid was uploaded without its texture");
    project_texture_kernel<<<blocks, block>>>(grid.view, static_cast<cudaTextureObject_t>(grid.texture), d, step, skip,
                                              image);
  } else if (read == Read::kSlices) {
    project_slices_kernel<<<blocks, block>>>(grid.view, d, skip, image);
  } else {
    project_kernel<<<blocks, block>>>(grid.view, d, step, skip, image);
  }
  check(cudaGetLastError(), "project_kernel launch");
}

}  // namespace

int device_count() {
  int n = 0;
  if (cudaGetDeviceCount(&n) != cudaSuccess) {
    cudaGetLastError();  // clear the sticky "no device" error
    return 0;
  }
  return n;
}

std::string device_name() {
  cudaDeviceProp p{};
  check(cudaGetDeviceProperties(&p, 0), "cudaGetDeviceProperties");
  return std::string(p.name) + " (sm_" + std::to_string(p.major) + std::to_string(p.minor) + ")";
}

DeviceGrid upload(const ray::GridView& host, size_t mu_count, size_t brick_count) {
  DeviceGrid g;
  g.view = host;
  try {
    check(cudaMalloc(&g.mu, mu_count * sizeof(float)), "cudaMalloc(mu)");
    check(cudaMalloc(&g.brick_max, brick_count * sizeof(float)), "cudaMalloc(brick_max)");
    check(cudaMemcpy(g.mu, host.mu, mu_count * sizeof(float), cudaMemcpyHostToDevice), "cudaMemcpy(mu)");
    check(cudaMemcpy(g.brick_max, host.brick_max, brick_count * sizeof(float), cudaMemcpyHostToDevice),
          "cudaMemcpy(brick_max)");
  } catch (...) {
    release(&g);
    throw;
  }
  g.view.mu = g.mu;
  g.view.brick_max = g.brick_max;
  g.view.brick_near = nullptr;  // (the CPU's packets alone walk it)
  return g;
}

void upload_texture(DeviceGrid* g, const ray::GridView& host) {
  // mu as a float 3-D array: trilinear filtering, unnormalised coordinates, zero border
  const cudaExtent extent = make_cudaExtent(host.nx, host.ny, host.nz);
  const cudaChannelFormatDesc format = cudaCreateChannelDesc<float>();
  cudaArray_t array = nullptr;
  check(cudaMalloc3DArray(&array, &format, extent), "cudaMalloc3DArray(mu)");
  try {
    cudaMemcpy3DParms copy{};
    copy.srcPtr = make_cudaPitchedPtr(const_cast<float*>(host.mu), host.nx * sizeof(float), host.nx, host.ny);
    copy.dstArray = array;
    copy.extent = extent;
    copy.kind = cudaMemcpyHostToDevice;
    check(cudaMemcpy3D(&copy), "cudaMemcpy3D(mu)");
    cudaResourceDesc resource{};
    resource.resType = cudaResourceTypeArray;
    resource.res.array.array = array;
    cudaTextureDesc sampling{};
    for (int a = 0; a < 3; ++a) sampling.addressMode[a] = cudaAddressModeBorder;
    sampling.filterMode = cudaFilterModeLinear;
    sampling.readMode = cudaReadModeElementType;
    sampling.normalizedCoords = 0;
    cudaTextureObject_t object = 0;
    check(cudaCreateTextureObject(&object, &resource, &sampling, nullptr), "cudaCreateTextureObject(mu)");
    g->texture = static_cast<unsigned long long>(object);
    g->texture_array = array;
  } catch (...) {
    cudaFreeArray(array);
    throw;
  }
}

void release(DeviceGrid* g) {
  if (g->texture) cudaDestroyTextureObject(static_cast<cudaTextureObject_t>(g->texture));
  if (g->texture_array) cudaFreeArray(static_cast<cudaArray_t>(g->texture_array));
  cudaFree(g->mu);
  cudaFree(g->brick_max);
  g->mu = g->brick_max = nullptr;
  g->texture = 0;
  g->texture_array = nullptr;
}

float* alloc_image(size_t pixels) {
  float* p = nullptr;
  check(cudaMalloc(&p, pixels * sizeof(float)), "cudaMalloc(image)");
  return p;
}

void free_image(float* image) {
  cudaFree(image);
}

void render(const DeviceGrid& grid, const ray::DetectorView& d, float step, bool skip, Read read, float* image) {
  launch(grid, d, step, skip, read, image);
  check(cudaDeviceSynchronize(), "project_kernel");
}

void download(const float* device_image, float* host, size_t pixels) {
  check(cudaMemcpy(host, device_image, pixels * sizeof(float), cudaMemcpyDeviceToHost), "cudaMemcpy(image)");
}

std::vector<float> time_render(const DeviceGrid& grid, const ray::DetectorView& d, float step, bool skip, Read read,
                               float* image, int warmup, int runs) {
  for (int i = 0; i < warmup; ++i) launch(grid, d, step, skip, read, image);
  check(cudaDeviceSynchronize(), "warm-up");
  cudaEvent_t start, stop;
  check(cudaEventCreate(&start), "cudaEventCreate");
  check(cudaEventCreate(&stop), "cudaEventCreate");
  std::vector<float> ms(runs);
  for (int i = 0; i < runs; ++i) {
    check(cudaEventRecord(start), "cudaEventRecord");
    launch(grid, d, step, skip, read, image);
    check(cudaEventRecord(stop), "cudaEventRecord");
    check(cudaEventSynchronize(stop), "cudaEventSynchronize");
    check(cudaEventElapsedTime(&ms[i], start, stop), "cudaEventElapsedTime");
  }
  cudaEventDestroy(start);
  cudaEventDestroy(stop);
  return ms;
}

}  // namespace pcisim::xray::cuda
