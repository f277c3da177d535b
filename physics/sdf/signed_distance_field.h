#pragma once
// Signed distance to the lumen wall on a regular grid: negative inside the lumen, positive in
// the wall. Sampled trilinearly; the gradient of the trilinear interpolant is the normal.
#include <Eigen/Core>
#include <vector>

#include "physics/geometry/triangle_mesh.h"

namespace pcisim::physics {

struct SdfSample {
  double distance_m = 0.0;   // < 0 inside the lumen
  Eigen::Vector3d gradient = Eigen::Vector3d::UnitX();  // unit length, points out of the lumen
  bool inside_grid = true;   // false: the point lies outside the grid (see sample())
};

class SignedDistanceField {
 public:
  // builds from a closed lumen mesh on a grid of spacing_m covering its bounds plus padding_m
  static SignedDistanceField build(const TriangleMesh& lumen, double spacing_m, double padding_m);

  // trilinear sample. Outside the grid the answer is safe and finite: see the implementation
  // comment for the exact rule.
  SdfSample sample(const Eigen::Vector3d& p_m) const;

  double spacing_m() const { return spacing_m_; }
  const Eigen::Vector3d& origin_m() const { return origin_m_; }
  const Eigen::Vector3i& dims() const { return dims_; }
  const std::vector<float>& values_m() const { return values_m_; }  // x fastest

 private:
  double spacing_m_ = 0.0;
  Eigen::Vector3d origin_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  std::vector<float> values_m_;
};

}  // namespace pcisim::physics
