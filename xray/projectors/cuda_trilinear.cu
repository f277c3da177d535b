// CUDA twin of the CPU trilinear marcher: one thread per detector pixel running the same
// ray::trilinear_ray as TrilinearProjector.
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

void launch(const DeviceGrid& grid, const ray::DetectorView& d, float step, bool skip, float* image) {
  const dim3 block(16, 8);
  const dim3 blocks((d.width + block.x - 1) / block.x, (d.height + block.y - 1) / block.y);
  project_kernel<<<blocks, block>>>(grid.view, d, step, skip, image);
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
  check(cudaMalloc(&g.mu, mu_count * sizeof(float)), "cudaMalloc(mu)");
  check(cudaMalloc(&g.brick_max, brick_count * sizeof(float)), "cudaMalloc(brick_max)");
  check(cudaMemcpy(g.mu, host.mu, mu_count * sizeof(float), cudaMemcpyHostToDevice), "cudaMemcpy(mu)");
  check(cudaMemcpy(g.brick_max, host.brick_max, brick_count * sizeof(float), cudaMemcpyHostToDevice),
        "cudaMemcpy(brick_max)");
  g.view.mu = g.mu;
  g.view.brick_max = g.brick_max;
  return g;
}

void release(DeviceGrid* g) {
  cudaFree(g->mu);
  cudaFree(g->brick_max);
  g->mu = g->brick_max = nullptr;
}

float* alloc_image(size_t pixels) {
  float* p = nullptr;
  check(cudaMalloc(&p, pixels * sizeof(float)), "cudaMalloc(image)");
  return p;
}

void free_image(float* image) {
  cudaFree(image);
}

void render(const DeviceGrid& grid, const ray::DetectorView& d, float step, bool skip, float* image) {
  launch(grid, d, step, skip, image);
  check(cudaDeviceSynchronize(), "project_kernel");
}

void download(const float* device_image, float* host, size_t pixels) {
  check(cudaMemcpy(host, device_image, pixels * sizeof(float), cudaMemcpyDeviceToHost), "cudaMemcpy(image)");
}

std::vector<float> time_render(const DeviceGrid& grid, const ray::DetectorView& d, float step, bool skip, float* image,
                               int warmup, int runs) {
  for (int i = 0; i < warmup; ++i) launch(grid, d, step, skip, image);
  check(cudaDeviceSynchronize(), "warm-up");
  cudaEvent_t start, stop;
  check(cudaEventCreate(&start), "cudaEventCreate");
  check(cudaEventCreate(&stop), "cudaEventCreate");
  std::vector<float> ms(runs);
  for (int i = 0; i < runs; ++i) {
    check(cudaEventRecord(start), "cudaEventRecord");
    launch(grid, d, step, skip, image);
    check(cudaEventRecord(stop), "cudaEventRecord");
    check(cudaEventSynchronize(stop), "cudaEventSynchronize");
    check(cudaEventElapsedTime(&ms[i], start, stop), "cudaEventElapsedTime");
  }
  cudaEventDestroy(start);
  cudaEventDestroy(stop);
  return ms;
}

}  // namespace pcisim::xray::cuda
