#pragma once
// A CT volume: a 3D grid of Hounsfield units with its place in patient space (LPS, mm).
// Voxel (i, j, k) has its centre at origin_mm + direction * (spacing_mm .* (i, j, k)); i runs
// fastest in memory. This is the ITK / MetaImage / NRRD convention, so files map one to one.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace pcisim::anatomy {

enum class VoxelType { kInt16, kFloat32 };

// "int16" or "float32"
const char* voxel_type_name(VoxelType type);
int voxel_type_bytes(VoxelType type);

struct Volume {
  std::array<int64_t, 3> dims{0, 0, 0};
  Eigen::Vector3d spacing_mm = Eigen::Vector3d::Ones();
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();      // centre of voxel (0, 0, 0)
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();  // column a: physical axis of index a
  VoxelType type = VoxelType::kInt16;
  std::vector<int16_t> hu_i16;  // used when type == kInt16
  std::vector<float> hu_f32;    // used when type == kFloat32

  // a zero-filled volume of the given size (allocates once)
  static Volume make(std::array<int64_t, 3> dims, const Eigen::Vector3d& spacing_mm, const Eigen::Vector3d& origin_mm,
                     VoxelType type);

  int64_t voxel_count() const { return dims[0] * dims[1] * dims[2]; }
  int64_t linear_index(int64_t i, int64_t j, int64_t k) const { return i + dims[0] * (j + dims[1] * k); }
  float hu(int64_t i, int64_t j, int64_t k) const {
    const int64_t n = linear_index(i, j, k);
    return type == VoxelType::kInt16 ? static_cast<float>(hu_i16[n]) : hu_f32[n];
  }
  // raw voxel bytes (little-endian on this machine) and their size
  const void* data() const;
  void* data();
  int64_t data_bytes() const { return voxel_count() * voxel_type_bytes(type); }

  // continuous index <-> physical (mm)
  Eigen::Vector3d index_to_physical_mm(const Eigen::Vector3d& ijk) const;
  Eigen::Vector3d physical_to_index(const Eigen::Vector3d& p_mm) const;
  // physical position of the volume's centre
  Eigen::Vector3d center_mm() const;
};

// empty string when the volume is usable (positive dims and spacing, invertible direction,
// data size matching dims), otherwise what is wrong
std::string validate(const Volume& volume);

}  // namespace pcisim::anatomy
