// CUDA twin of the CPU B-mode renderer: the rules of bmode_kernels.h on device arrays. The march
// and the running products along a scanline are one thread a scanline; the rest one a sample or
// pixel (the CPU's echo_scanline split into its rules: the same arithmetic in the same order). Compiled without fused
// multiply-adds (CMake: --fmad=false) so the arithmetic is the CPU's; the math library's exp and log may differ from
// glibc's in the last place.
#include <cuda_runtime.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "ultrasound/echo/acoustic_model.h"
#include "ultrasound/render/cuda_bmode.h"

namespace pcisim::ultrasound::cuda {
namespace {

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw std::runtime_error(std::string("CUDA ") + what + ": " + cudaGetErrorString(e));
}

template <class T>
T* alloc(size_t count, const char* what) {
  void* p = nullptr;
  check(cudaMalloc(&p, count * sizeof(T) + 1), what);
  return static_cast<T*>(p);
}

template <class T>
void put(T* device, const T* host, size_t count, const char* what) {
  if (count) check(cudaMemcpy(device, host, count * sizeof(T), cudaMemcpyHostToDevice), what);
}

// a device array that grows to what is asked of it
template <class T>
struct Grow {
  T* p = nullptr;
  size_t capacity = 0;
  T* fit(size_t count, const char* what) {
    if (count > capacity) {
      cudaFree(p);
      p = nullptr;
      capacity = 0;
      p = alloc<T>(count, what);
      capacity = count;
    }
    return p;
  }
  ~Grow() { cudaFree(p); }
};

struct LabelSampler {
  kernels::LabelView v;
  __device__ Acoustics operator()(const double (&q)[3]) const { return kernels::sample_labels(v, q); }
};

__global__ void march_kernel(kernels::FrameView f, kernels::PoseView pose, LocatorView locator, bool mapped,
                             const Cf* table, uint64_t mixed_seed, LabelSampler sample) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c >= f.width) return;
  kernels::march_scanline(f, pose, mapped ? &locator : nullptr, table, mixed_seed, sample, c);
}

// the echo's rules that need only the march's results, one thread a sample (n = c h + j):
// the scatterer, Z's smoothed change, the step's loss and transmission factors
__global__ void sample_kernel(kernels::FrameView f, const Cf* table, uint64_t mixed_seed) {
  const int64_t n = static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (n >= static_cast<int64_t>(f.width) * f.height) return;
  const int c = static_cast<int>(n / f.height), j = static_cast<int>(n % f.height);
  kernels::scatter_sample(f, table, mixed_seed, n);
  f.steepness[n] = kernels::steepness_sample(f, c, j);
  f.half_step[n] = kernels::half_step_factor(kernels::loss_db(f, n));
  f.transmission[n] = kernels::transmission_factor(f, c, j);
}

__global__ void amplitude_kernel(kernels::FrameView f) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x;
  if (c < f.width) kernels::amplitude_scanline(f, c);
}

__global__ void field_kernel(kernels::FrameView f) {
  const int64_t n = static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (n >= static_cast<int64_t>(f.width) * f.height) return;
  const int c = static_cast<int>(n / f.height), j = static_cast<int>(n % f.height);
  f.field[n] = kernels::echo_field(f, c, j, f.amplitude[n]);
}

__global__ void axial_kernel(kernels::FrameView f) {
  const int j = blockIdx.x * blockDim.x + threadIdx.x, c = blockIdx.y;
  if (j < f.height) kernels::axial_sample(f, c, j);
}

__global__ void lateral_kernel(kernels::FrameView f) {
  const int c = blockIdx.x * blockDim.x + threadIdx.x, r = blockIdx.y;
  if (c < f.width) kernels::lateral_pixel(f, r, c);
}

__global__ void convert_kernel(kernels::FrameView f) {
  const int64_t k = static_cast<int64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (k < static_cast<int64_t>(f.width) * f.height) kernels::scan_convert_pixel(f, k);
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

struct BModeDevice::Buffers {
  kernels::LabelView labels;  // device pointers
  Cf* table = nullptr;
  kernels::FrameView frame;  // device pointers; the scalars are each render()'s
  int64_t samples = 0;
  LocatorView locator;  // device pointers
  Grow<double> inv_current, v0_current, edges_rest, v0_rest;
  Grow<unsigned char> valid;
  Grow<int> cell_start, entries;
  cudaEvent_t mark[kPasses + 1] = {};  // before each pass, and after the last
  std::vector<void*> owned;
  std::vector<void*> pinned;
  template <class T>
  T* own(size_t count, const char* what) {
    T* p = alloc<T>(count, what);
    owned.push_back(p);
    return p;
  }
  ~Buffers() {
    for (void* p : owned) cudaFree(p);
    for (void* p : pinned) cudaHostUnregister(p);
    for (cudaEvent_t e : mark)
      if (e) cudaEventDestroy(e);
  }
};

BModeDevice::BModeDevice(const kernels::LabelView& labels, int64_t voxels, int label_count, int width, int height)
    : b_(new Buffers) {
  try {
    if (device_count() == 0) throw std::runtime_error("CUDA: no device visible");
    Buffers& b = *b_;
    b.labels = labels;
    int16_t* l = b.own<int16_t>(voxels, "cudaMalloc labels");
    put(l, labels.labels, voxels, "cudaMemcpy labels");
    b.labels.labels = l;
    Acoustics* a = b.own<Acoustics>(label_count, "cudaMalloc acoustics");
    put(a, labels.acoustics, label_count, "cudaMemcpy acoustics");
    b.labels.acoustics = a;
    b.table = b.own<Cf>(kScatterers, "cudaMalloc scatterers");
    put(b.table, scatterer_table(), kScatterers, "cudaMemcpy scatterers");
    const int64_t n = static_cast<int64_t>(width) * height;
    b.samples = n;
    kernels::FrameView& f = b.frame;
    f.width = width;
    f.height = height;
    constexpr int taps = 2 * kernels::kMaxKernelHalf + 1;
    f.line_start = b.own<double>(2 * width, "cudaMalloc");
    f.line_dir = b.own<double>(2 * width, "cudaMalloc");
    f.z = b.own<float>(n, "cudaMalloc");
    f.path_ratio = b.own<float>(n, "cudaMalloc");
    f.attenuation = b.own<float>(n, "cudaMalloc");
    f.scatter_amplitude = b.own<float>(n, "cudaMalloc");
    f.scatterer = b.own<Cf>(n, "cudaMalloc");
    f.field = b.own<Cf>(n, "cudaMalloc");
    f.axial = b.own<Cf>(n, "cudaMalloc");
    f.steepness = b.own<float>(n, "cudaMalloc");
    f.echo = b.own<float>(n, "cudaMalloc");
    f.rest_cells = b.own<double>(3 * n, "cudaMalloc");
    f.half_step = b.own<double>(n, "cudaMalloc");
    f.transmission = b.own<double>(n, "cudaMalloc");
    f.amplitude = b.own<double>(n, "cudaMalloc");
    f.beam = b.own<uint8_t>(n, "cudaMalloc");
    f.image = b.own<uint8_t>(n, "cudaMalloc");
    f.axial_kernel = b.own<float>(taps, "cudaMalloc");
    f.steep_kernel = b.own<float>(taps, "cudaMalloc");
    f.lateral_kernel = b.own<float>(static_cast<size_t>(taps) * height, "cudaMalloc");
    f.line_spacing_mm = b.own<float>(height, "cudaMalloc");
    f.scatter_scale = b.own<float>(height, "cudaMalloc");
    f.lateral_half = b.own<int>(height, "cudaMalloc");
    f.convert_index = b.own<int>(n, "cudaMalloc");
    f.convert_fx = b.own<float>(n, "cudaMalloc");
    f.convert_fy = b.own<float>(n, "cudaMalloc");
    for (cudaEvent_t& e : b.mark) check(cudaEventCreate(&e), "cudaEventCreate");
  } catch (...) {
    delete b_;
    throw;
  }
}

BModeDevice::~BModeDevice() {
  delete b_;
}

void BModeDevice::upload_geometry(const kernels::FrameView& host, bool curved) {
  kernels::FrameView& f = b_->frame;
  const int w = f.width, h = f.height;
  const size_t n = static_cast<size_t>(b_->samples);
  constexpr int taps = 2 * kernels::kMaxKernelHalf + 1;
  put(const_cast<double*>(f.line_start), host.line_start, 2 * w, "cudaMemcpy line_start");
  put(const_cast<double*>(f.line_dir), host.line_dir, 2 * w, "cudaMemcpy line_dir");
  put(const_cast<float*>(f.axial_kernel), host.axial_kernel, taps, "cudaMemcpy axial_kernel");
  put(const_cast<float*>(f.steep_kernel), host.steep_kernel, taps, "cudaMemcpy steep_kernel");
  put(const_cast<float*>(f.lateral_kernel), host.lateral_kernel, static_cast<size_t>(taps) * h,
      "cudaMemcpy lateral_kernel");
  put(const_cast<float*>(f.line_spacing_mm), host.line_spacing_mm, h, "cudaMemcpy line_spacing");
  put(const_cast<float*>(f.scatter_scale), host.scatter_scale, h, "cudaMemcpy scatter_scale");
  put(const_cast<int*>(f.lateral_half), host.lateral_half, h, "cudaMemcpy lateral_half");
  if (curved) {
    put(const_cast<int*>(f.convert_index), host.convert_index, n, "cudaMemcpy convert_index");
    put(const_cast<float*>(f.convert_fx), host.convert_fx, n, "cudaMemcpy convert_fx");
    put(const_cast<float*>(f.convert_fy), host.convert_fy, n, "cudaMemcpy convert_fy");
  }
  f.axial_half = host.axial_half;
  f.steep_half = host.steep_half;
}

void BModeDevice::download_echo(float* host) const {
  const size_t n = static_cast<size_t>(b_->samples);
  check(cudaMemcpy(host, b_->frame.echo, n * sizeof(float), cudaMemcpyDeviceToHost), "cudaMemcpy echo");
}

void BModeDevice::pin(void* host, size_t bytes) {
  if (!host || bytes == 0) return;
  check(cudaHostRegister(host, bytes, cudaHostRegisterDefault), "cudaHostRegister");
  b_->pinned.push_back(host);
}

void BModeDevice::upload_rest(const LocatorView& host) {
  Buffers& b = *b_;
  const size_t t = static_cast<size_t>(host.tet_count);
  b.locator.edges_rest = b.edges_rest.fit(9 * t, "cudaMalloc edges_rest");
  put(const_cast<double*>(b.locator.edges_rest), host.edges_rest, 9 * t, "cudaMemcpy edges_rest");
  b.locator.v0_rest = b.v0_rest.fit(3 * t, "cudaMalloc v0_rest");
  put(const_cast<double*>(b.locator.v0_rest), host.v0_rest, 3 * t, "cudaMemcpy v0_rest");
}

void BModeDevice::render(const kernels::FrameView& host, const kernels::PoseView& pose, const LocatorView* locator,
                         int cells, int entries, long entries_capacity, uint64_t mixed_seed, bool curved) {
  Buffers& b = *b_;
  // the scalars of this frame, the arrays the device's
  kernels::FrameView f = b.frame;
  f.dx_mm = host.dx_mm;
  f.depth_mm = host.depth_mm;
  f.pulse_mm = host.pulse_mm;
  f.voxel_mm = host.voxel_mm;
  f.speckle_cell_mm = host.speckle_cell_mm;
  f.attenuation_db_per_cm_mhz = host.attenuation_db_per_cm_mhz;
  f.frequency_mhz = host.frequency_mhz;
  f.specular_exponent = host.specular_exponent;
  f.gain_db = host.gain_db;
  f.tgc_db_per_cm = host.tgc_db_per_cm;
  f.dynamic_range_db = host.dynamic_range_db;
  if (locator) {
    const size_t t = static_cast<size_t>(locator->tet_count);
    LocatorView& l = b.locator;
    l.tet_count = locator->tet_count;
    for (int k = 0; k < 3; ++k) {
      l.dims[k] = locator->dims[k];
      l.lo[k] = locator->lo[k];
      l.inv_cell[k] = locator->inv_cell[k];
    }
    l.inv_current = b.inv_current.fit(9 * t, "cudaMalloc inv_current");
    put(const_cast<double*>(l.inv_current), locator->inv_current, 9 * t, "cudaMemcpy inv_current");
    l.v0_current = b.v0_current.fit(3 * t, "cudaMalloc v0_current");
    put(const_cast<double*>(l.v0_current), locator->v0_current, 3 * t, "cudaMemcpy v0_current");
    l.valid = b.valid.fit(t, "cudaMalloc valid");
    put(const_cast<unsigned char*>(l.valid), locator->valid, t, "cudaMemcpy valid");
    l.cell_start = b.cell_start.fit(cells + 1, "cudaMalloc cell_start");
    put(const_cast<int*>(l.cell_start), locator->cell_start, cells + 1, "cudaMemcpy cell_start");
    l.entries = b.entries.fit(std::max<size_t>(entries, entries_capacity), "cudaMalloc entries");
    put(const_cast<int*>(l.entries), locator->entries, entries, "cudaMemcpy entries");
  }
  const int w = f.width, h = f.height;
  // a scanline a thread: 256 threads, each a chain of dependent loads (tet, labels, tissue), spread
  // one a block over the SMs. The curvilinear kidney's march on an H200 (median of 100 frames):
  // blocks of 32 threads 1.25 ms, 16 0.91, 8 0.76, 4 0.63, 2 0.57, 1 0.53 (docs/benchmarks/ultrasound.md)
  constexpr int kLine = 1, kBlock = 128;
  check(cudaEventRecord(b.mark[0]), "cudaEventRecord");
  march_kernel<<<(w + kLine - 1) / kLine, kLine>>>(f, pose, b.locator, locator != nullptr, b.table, mixed_seed,
                                                   LabelSampler{b.labels});
  check(cudaEventRecord(b.mark[1]), "cudaEventRecord");
  const auto sample_blocks = static_cast<unsigned>((b.samples + kBlock - 1) / kBlock);
  sample_kernel<<<sample_blocks, kBlock>>>(f, b.table, mixed_seed);
  amplitude_kernel<<<(w + kLine - 1) / kLine, kLine>>>(f);
  field_kernel<<<sample_blocks, kBlock>>>(f);
  check(cudaEventRecord(b.mark[2]), "cudaEventRecord");
  axial_kernel<<<dim3((h + kBlock - 1) / kBlock, w), kBlock>>>(f);
  check(cudaEventRecord(b.mark[3]), "cudaEventRecord");
  lateral_kernel<<<dim3((w + kBlock - 1) / kBlock, h), kBlock>>>(f);
  check(cudaEventRecord(b.mark[4]), "cudaEventRecord");
  if (curved) convert_kernel<<<sample_blocks, kBlock>>>(f);
  check(cudaGetLastError(), "B-mode kernel launch");
  check(cudaEventRecord(b.mark[kPasses]), "cudaEventRecord");
  check(cudaEventSynchronize(b.mark[kPasses]), "B-mode kernels");
  check(cudaEventElapsedTime(&last_kernel_ms_, b.mark[0], b.mark[kPasses]), "cudaEventElapsedTime");
  for (int k = 0; k < kPasses; ++k)
    check(cudaEventElapsedTime(&last_pass_ms_[k], b.mark[k], b.mark[k + 1]), "cudaEventElapsedTime");
  const size_t n = static_cast<size_t>(b.samples);
  check(cudaMemcpy(host.beam, f.beam, n, cudaMemcpyDeviceToHost), "cudaMemcpy beam");
  if (curved) check(cudaMemcpy(host.image, f.image, n, cudaMemcpyDeviceToHost), "cudaMemcpy image");
}

}  // namespace pcisim::ultrasound::cuda
