#pragma once
// Signed distance to the lumen wall on a regular grid: negative inside the lumen, positive in
// the wall. Sampled trilinearly; the gradient of the trilinear interpolant is the normal.
// Storage is sparse: the grid is cut into 8x8x8 bricks and only bricks within the band of the
// surface hold values; the rest are uniformly +band (outside) or -band (inside). Build and
// rules: docs/anatomy.md ("Signed distance field").
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "anatomy/mesh/triangle_mesh.h"

namespace pcisim::physics {

struct SdfSample {
  double distance_m = 0.0;                              // < 0 inside the lumen
  Eigen::Vector3d gradient = Eigen::Vector3d::UnitX();  // unit length, points out of the lumen
  bool inside_grid = true;                              // false: the point lies outside the grid (see sample())
};

struct SdfBuildSpec {
  double spacing_m = 0.2e-3;  // grid spacing
  double padding_m = 1.0e-3;  // the grid covers the mesh's bounds plus this on every side
  double band_m = 0.0;        // exact distances within this of the wall; 0 picks 4 cells
};

class SignedDistanceField {
 public:
  static constexpr int kBrick = 8;  // grid points per brick edge

  // builds from a closed lumen mesh on a grid of spacing_m covering its bounds plus padding_m.
  // The mesh may hold several closed tubes (connected components); the lumen is their union.
  // Throws std::invalid_argument for an empty mesh, spacing <= 0 or a grid over 2^31 points.
  static SignedDistanceField build(const anatomy::TriangleMesh& lumen, double spacing_m, double padding_m);
  static SignedDistanceField build(const anatomy::TriangleMesh& lumen, const SdfBuildSpec& spec);

  // trilinear sample. Outside the grid the answer is safe and finite: see the implementation
  // comment for the exact rule. Allocates nothing.
  SdfSample sample(const Eigen::Vector3d& p_m) const;
  // sample() for each of n points (plain pointers: this header is also read by nvcc in C++17)
  void sample_many(const Eigen::Vector3d* points_m, size_t n, SdfSample* out) const;

  double spacing_m() const { return spacing_m_; }
  const Eigen::Vector3d& origin_m() const { return origin_m_; }
  const Eigen::Vector3i& dims() const { return dims_; }  // grid points per axis, multiples of 8
  double band_m() const { return band_m_; }
  // value at grid point (i, j, k), each index within [0, dims)
  float value_at(int i, int j, int k) const;

  // the brick pool: kBrick^3 values per allocated brick, x fastest within a brick (this is not a
  // dense x-fastest grid: use value_at() or brick_table() to address it)
  const std::vector<float>& values_m() const { return values_m_; }
  // one entry per brick (x fastest): a pool brick index, -1 uniformly +band, -2 uniformly -band
  const std::vector<int32_t>& brick_table() const { return brick_table_; }
  Eigen::Vector3i brick_dims() const { return dims_ / kBrick; }
  size_t memory_bytes() const { return values_m_.size() * sizeof(float) + brick_table_.size() * sizeof(int32_t); }

  // assembles a field from its parts (the CUDA twin's builder uses it)
  static SignedDistanceField from_parts(double spacing_m, const Eigen::Vector3d& origin_m, const Eigen::Vector3i& dims,
                                        double band_m, std::vector<int32_t> brick_table, std::vector<float> values_m);

 private:
  double spacing_m_ = 0.0;
  Eigen::Vector3d origin_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  std::vector<float> values_m_;
  double band_m_ = 0.0;
  std::vector<int32_t> brick_table_;
};

}  // namespace pcisim::physics
