#pragma once
// CUDA twins of the SDF build and of batched sampling (compiled only when CUDA is found; the CPU
// twins are SignedDistanceField::build and ::sample). Both run the same arithmetic from
// sdf_kernels.h; the comparison and its tolerance are in tests/physics/sdf/.
#include <cstdint>
#include <memory>
#include <string>

#include "physics/sdf/signed_distance_field.h"

namespace pcisim::physics {

// true when a CUDA device can be used; otherwise false and, if why is given, the reason
bool cuda_sdf_available(std::string* why = nullptr);

struct CudaSdfBuildTimings {
  double plan_ms = 0.0;       // CPU: grid, bricks, components, parity rows
  double kernels_ms = 0.0;    // GPU: reset + rasterize + fold kernels, by CUDA events
  double transfer_ms = 0.0;   // uploads and the pool's download
  double remainder_ms = 0.0;  // CPU: classify_remaining
};

// the GPU twin of SignedDistanceField::build: one thread per triangle rasterizes the prisms with
// 64-bit atomicMin on (distance float bits, triangle index); one thread per brick point folds the
// tube into the union. Throws std::runtime_error on a CUDA error.
SignedDistanceField build_sdf_cuda(const anatomy::TriangleMesh& lumen, const SdfBuildSpec& spec,
                                   CudaSdfBuildTimings* timings = nullptr);

// a field copied to the GPU for batched queries: n points in, distance + unit gradient out
class CudaSdfSampler {
 public:
  explicit CudaSdfSampler(const SignedDistanceField& field);
  ~CudaSdfSampler();
  CudaSdfSampler(const CudaSdfSampler&) = delete;
  CudaSdfSampler& operator=(const CudaSdfSampler&) = delete;

  // host arrays: points_m[3n] in, distance_m[n], gradient[3n], inside_grid[n] out
  void sample(const double* points_m, int n, double* distance_m, double* gradient, uint8_t* inside_grid);
  // device arrays of the same shapes, no copies; returns the kernel time in ms (CUDA events)
  double sample_device(const double* points_m, int n, double* distance_m, double* gradient, uint8_t* inside_grid);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pcisim::physics
