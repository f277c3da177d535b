// eigen (through the public header) trips nvcc's note on defaulted __host__ __device__ members
#pragma nv_diag_suppress 20012
#include "physics/sdf/signed_distance_field_cuda.h"

#include <cuda_runtime.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include "physics/sdf/sdf_build_plan.h"
#include "physics/sdf/sdf_kernels.h"

namespace pcisim::physics {
namespace {

using namespace sdf;

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw std::runtime_error(std::string("CUDA ") + what + ": " + cudaGetErrorString(e));
}

template <class T>
struct DeviceArray {
  T* ptr = nullptr;
  size_t n = 0;
  DeviceArray() = default;
  explicit DeviceArray(size_t count) : n(count) {
    if (n) check(cudaMalloc(&ptr, n * sizeof(T)), "cudaMalloc");
  }
  DeviceArray(const std::vector<T>& host) : DeviceArray(host.size()) {
    if (n) check(cudaMemcpy(ptr, host.data(), n * sizeof(T), cudaMemcpyHostToDevice), "upload");
  }
  ~DeviceArray() {
    if (ptr) cudaFree(ptr);
  }
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
};

struct AtomicMinKey {
  __device__ void operator()(uint64_t* slot, uint64_t key) const {
    atomicMin(reinterpret_cast<unsigned long long*>(slot), static_cast<unsigned long long>(key));
  }
};

__global__ void reset_keys(const int32_t* bricks, uint64_t* keys) {
  keys[int64_t(bricks[blockIdx.x]) * kBrickPoints + threadIdx.x] = kNoKey;
}

// one thread per triangle: the paper's prism, its AABB, exact distances (eq 13), atomic min
__global__ void rasterize(BuildGrid g, const Triangle* triangles, const uint32_t* list, int count, uint64_t* keys) {
  const int t = blockIdx.x * blockDim.x + threadIdx.x;
  if (t >= count) return;
  const uint32_t index = list[t];
  rasterize_triangle(g, triangles[index], index, keys, AtomicMinKey{});
}

// one block per brick, one thread per point: eq 14 sign (parity where ambiguous), min into union
__global__ void fold(BuildGrid g, const Triangle* triangles, ParityView pv, const int32_t* bricks,
                     const int32_t* brick_coords, const uint64_t* keys, float* pool) {
  const int32_t b = bricks[blockIdx.x];
  const int l = threadIdx.x;
  const int i = brick_coords[3 * b] * kBrick + l % kBrick;
  const int j = brick_coords[3 * b + 1] * kBrick + (l / kBrick) % kBrick;
  const int k = brick_coords[3 * b + 2] * kBrick + l / (kBrick * kBrick);
  const int64_t idx = int64_t(b) * kBrickPoints + l;
  const float v = component_value(g, triangles, pv, keys[idx], i, j, k);
  if (v < pool[idx]) pool[idx] = v;  // one thread owns this point within a component
}

__global__ void sample_points(GridView g, const double* p, int n, double* d, double* grad, uint8_t* inside) {
  const int t = blockIdx.x * blockDim.x + threadIdx.x;
  if (t >= n) return;
  bool in;
  sample_grid(g, p + 3 * int64_t(t), d + t, grad + 3 * int64_t(t), &in);
  inside[t] = in ? 1 : 0;
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

bool cuda_sdf_available(std::string* why) {
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess) {
    if (why) *why = std::string("cudaGetDeviceCount failed: ") + cudaGetErrorString(e);
    return false;
  }
  if (count == 0) {
    if (why) *why = "no CUDA device present";
    return false;
  }
  return true;
}

SignedDistanceField build_sdf_cuda(const anatomy::TriangleMesh& lumen, const SdfBuildSpec& spec,
                                   CudaSdfBuildTimings* timings) {
  CudaSdfBuildTimings local;
  CudaSdfBuildTimings& tm = timings ? *timings : local;
  auto t0 = std::chrono::steady_clock::now();
  BuildPlan plan = make_build_plan(lumen, spec.spacing_m, spec.padding_m, spec.band_m);
  tm.plan_ms = ms_since(t0);

  // every component's lists in one upload, addressed by offsets
  t0 = std::chrono::steady_clock::now();
  std::vector<uint32_t> tri_list;
  std::vector<int32_t> brick_list, row_begin;
  std::vector<double> xs;
  struct Offsets {
    size_t tri, tri_n, brick, brick_n, row, x;
  };
  std::vector<Offsets> off;
  for (const ComponentPlan& c : plan.components) {
    off.push_back(
        {tri_list.size(), c.triangles.size(), brick_list.size(), c.bricks.size(), row_begin.size(), xs.size()});
    tri_list.insert(tri_list.end(), c.triangles.begin(), c.triangles.end());
    brick_list.insert(brick_list.end(), c.bricks.begin(), c.bricks.end());
    row_begin.insert(row_begin.end(), c.row_begin.begin(), c.row_begin.end());
    xs.insert(xs.end(), c.xs.begin(), c.xs.end());
  }
  const size_t pool_n = size_t(plan.pool_bricks()) * kBrickPoints;
  std::vector<float> pool(pool_n, plan.grid.band);
  DeviceArray<Triangle> d_tri(plan.triangles);
  DeviceArray<uint32_t> d_list(tri_list);
  DeviceArray<int32_t> d_bricks(brick_list), d_rows(row_begin), d_table(plan.table), d_coords(plan.pool_brick_coords);
  DeviceArray<double> d_xs(xs);
  DeviceArray<float> d_pool(pool);
  DeviceArray<uint64_t> d_keys(pool_n);
  tm.transfer_ms = ms_since(t0);

  BuildGrid g = plan.grid;
  g.table = d_table.ptr;
  cudaEvent_t start, stop;
  check(cudaEventCreate(&start), "event");
  check(cudaEventCreate(&stop), "event");
  check(cudaEventRecord(start), "event");
  for (size_t ci = 0; ci < plan.components.size(); ++ci) {
    const ComponentPlan& c = plan.components[ci];
    const Offsets& o = off[ci];
    if (o.brick_n == 0) continue;
    reset_keys<<<unsigned(o.brick_n), kBrickPoints>>>(d_bricks.ptr + o.brick, d_keys.ptr);
    const int threads = 128;
    rasterize<<<unsigned((o.tri_n + threads - 1) / threads), threads>>>(g, d_tri.ptr, d_list.ptr + o.tri, int(o.tri_n),
                                                                        d_keys.ptr);
    const ParityView pv{c.j0, c.j1, c.k0, c.k1, d_rows.ptr + o.row, d_xs.ptr + o.x};
    fold<<<unsigned(o.brick_n), kBrickPoints>>>(g, d_tri.ptr, pv, d_bricks.ptr + o.brick, d_coords.ptr, d_keys.ptr,
                                                d_pool.ptr);
  }
  check(cudaGetLastError(), "kernel launch");
  check(cudaEventRecord(stop), "event");
  check(cudaEventSynchronize(stop), "kernels");
  float kernel_ms = 0;
  cudaEventElapsedTime(&kernel_ms, start, stop);
  cudaEventDestroy(start);
  cudaEventDestroy(stop);
  tm.kernels_ms = kernel_ms;

  t0 = std::chrono::steady_clock::now();
  check(cudaMemcpy(pool.data(), d_pool.ptr, pool_n * sizeof(float), cudaMemcpyDeviceToHost), "download");
  tm.transfer_ms += ms_since(t0);

  t0 = std::chrono::steady_clock::now();
  classify_remaining(plan, pool);
  tm.remainder_ms = ms_since(t0);
  const BuildGrid& hg = plan.grid;
  return SignedDistanceField::from_parts(hg.spacing, Eigen::Vector3d(hg.origin[0], hg.origin[1], hg.origin[2]),
                                         Eigen::Vector3i(hg.dims[0], hg.dims[1], hg.dims[2]), hg.band,
                                         std::move(plan.table), std::move(pool));
}

struct CudaSdfSampler::Impl {
  GridView view{};
  DeviceArray<int32_t> table;
  DeviceArray<float> pool;
  // scratch for the host-array call, grown as needed (not per call)
  DeviceArray<double> p, d, grad;
  DeviceArray<uint8_t> inside;
  size_t capacity = 0;
  cudaEvent_t start{}, stop{};
  Impl(const SignedDistanceField& f) : table(f.brick_table()), pool(f.values_m()) {
    for (int a = 0; a < 3; ++a) {
      view.origin[a] = f.origin_m()[a];
      view.dims[a] = f.dims()[a];
      view.bricks[a] = f.dims()[a] / SignedDistanceField::kBrick;
    }
    view.spacing = f.spacing_m();
    view.band = float(f.band_m());
    view.table = table.ptr;
    view.pool = pool.ptr;
    check(cudaEventCreate(&start), "event");
    check(cudaEventCreate(&stop), "event");
  }
  ~Impl() {
    cudaEventDestroy(start);
    cudaEventDestroy(stop);
  }
};

CudaSdfSampler::CudaSdfSampler(const SignedDistanceField& field) : impl_(std::make_unique<Impl>(field)) {}
CudaSdfSampler::~CudaSdfSampler() = default;

double CudaSdfSampler::sample_device(const double* points_m, int n, double* distance_m, double* gradient,
                                     uint8_t* inside_grid) {
  if (n <= 0) return 0.0;
  const int threads = 256;
  check(cudaEventRecord(impl_->start), "event");
  sample_points<<<(n + threads - 1) / threads, threads>>>(impl_->view, points_m, n, distance_m, gradient, inside_grid);
  check(cudaGetLastError(), "sample launch");
  check(cudaEventRecord(impl_->stop), "event");
  check(cudaEventSynchronize(impl_->stop), "sample");
  float ms = 0;
  cudaEventElapsedTime(&ms, impl_->start, impl_->stop);
  return ms;
}

void CudaSdfSampler::sample(const double* points_m, int n, double* distance_m, double* gradient, uint8_t* inside_grid) {
  if (n <= 0) return;
  Impl& m = *impl_;
  if (size_t(n) > m.capacity) {
    m.p.~DeviceArray();
    new (&m.p) DeviceArray<double>(3 * size_t(n));
    m.d.~DeviceArray();
    new (&m.d) DeviceArray<double>(size_t(n));
    m.grad.~DeviceArray();
    new (&m.grad) DeviceArray<double>(3 * size_t(n));
    m.inside.~DeviceArray();
    new (&m.inside) DeviceArray<uint8_t>(size_t(n));
    m.capacity = n;
  }
  check(cudaMemcpy(m.p.ptr, points_m, 3 * sizeof(double) * n, cudaMemcpyHostToDevice), "upload points");
  sample_device(m.p.ptr, n, m.d.ptr, m.grad.ptr, m.inside.ptr);
  check(cudaMemcpy(distance_m, m.d.ptr, sizeof(double) * n, cudaMemcpyDeviceToHost), "download");
  check(cudaMemcpy(gradient, m.grad.ptr, 3 * sizeof(double) * n, cudaMemcpyDeviceToHost), "download");
  check(cudaMemcpy(inside_grid, m.inside.ptr, n, cudaMemcpyDeviceToHost), "download");
}

}  // namespace pcisim::physics
