#pragma once
// The images of the modeling pipeline: a grid (the CT's voxel geometry) with a mask or a float
// field on it. Voxel (i, j, k) is at origin_mm + direction * (spacing_mm .* (i, j, k)), i fastest,
// as anatomy::Volume. A crop keeps the parent's physical frame, so physical points never move.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>
#include "anatomy/volume/volume.h"

namespace pcisim::modeling {

struct ImageGrid {
  std::array<int64_t, 3> dims{0, 0, 0};
  Eigen::Vector3d spacing_mm = Eigen::Vector3d::Ones();
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();

  static ImageGrid of(const anatomy::Volume& v);
  int64_t size() const { return dims[0] * dims[1] * dims[2]; }
  int64_t index(int64_t i, int64_t j, int64_t k) const { return i + dims[0] * (j + dims[1] * k); }
  std::array<int64_t, 3> ijk(int64_t n) const {
    return {n % dims[0], (n / dims[0]) % dims[1], n / (dims[0] * dims[1])};
  }
  bool inside(int64_t i, int64_t j, int64_t k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < dims[0] && j < dims[1] && k < dims[2];
  }
  Eigen::Vector3d physical_mm(const Eigen::Vector3d& ijk) const;
  Eigen::Vector3d continuous_index(const Eigen::Vector3d& p_mm) const;
  // the sub-grid [lo, lo + dims) of this one, in the same physical frame
  ImageGrid crop(const std::array<int64_t, 3>& lo, const std::array<int64_t, 3>& dims) const;
};

// "" when b lies on a's grid (same dims and direction, spacing to 1e-6 relative, origin to 1e-6
// of a voxel), else what differs: "dims 40 x 40 x 39 differ from 40 x 40 x 40", "spacing differs", ...
std::string grid_difference(const ImageGrid& b, const ImageGrid& a);

struct Mask {
  ImageGrid grid;
  std::vector<uint8_t> v;  // 0 or 1 (or small labels)
  static Mask zeros(const ImageGrid& g) { return {g, std::vector<uint8_t>(g.size(), 0)}; }
  int64_t count() const;
};

struct FloatImage {
  ImageGrid grid;
  std::vector<float> v;
  // trilinear at a continuous index; `outside` beyond the grid
  float at(const Eigen::Vector3d& ijk, float outside) const;
};

// the CT's HU as floats on the sub-grid [lo, lo + dims) (the whole volume when dims are its own)
FloatImage crop_hu(const anatomy::Volume& ct, const std::array<int64_t, 3>& lo, const std::array<int64_t, 3>& dims);

// the bounding box of a mask's set voxels grown by margin voxels and clamped to the grid;
// dims of zero when the mask is empty
void bounding_box(const Mask& m, int64_t margin, std::array<int64_t, 3>* lo, std::array<int64_t, 3>* dims);

// 26-connected face/edge/corner neighbour offsets and their lengths in mm on a grid
struct Neighbours26 {
  std::array<std::array<int, 3>, 26> d;
  std::array<double, 26> length_mm;
  explicit Neighbours26(const Eigen::Vector3d& spacing_mm);
};

}  // namespace pcisim::modeling
