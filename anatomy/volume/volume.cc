#include "anatomy/volume/volume.h"

#include <Eigen/LU>
#include <cmath>
#include <fmt/format.h>

namespace pcisim::anatomy {

const char* voxel_type_name(VoxelType type) {
  return type == VoxelType::kInt16 ? "int16" : "float32";
}

int voxel_type_bytes(VoxelType type) {
  return type == VoxelType::kInt16 ? 2 : 4;
}

Volume Volume::make(std::array<int64_t, 3> dims, const Eigen::Vector3d& spacing_mm, const Eigen::Vector3d& origin_mm,
                    VoxelType type) {
  Volume v;
  v.dims = dims;
  v.spacing_mm = spacing_mm;
  v.origin_mm = origin_mm;
  v.type = type;
  if (type == VoxelType::kInt16) {
    v.hu_i16.assign(v.voxel_count(), 0);
  } else {
    v.hu_f32.assign(v.voxel_count(), 0.0f);
  }
  return v;
}

const void* Volume::data() const {
  return type == VoxelType::kInt16 ? static_cast<const void*>(hu_i16.data()) : static_cast<const void*>(hu_f32.data());
}

void* Volume::data() {
  return type == VoxelType::kInt16 ? static_cast<void*>(hu_i16.data()) : static_cast<void*>(hu_f32.data());
}

Eigen::Vector3d Volume::index_to_physical_mm(const Eigen::Vector3d& ijk) const {
  return origin_mm + direction * spacing_mm.cwiseProduct(ijk);
}

Eigen::Vector3d Volume::physical_to_index(const Eigen::Vector3d& p_mm) const {
  return (direction.inverse() * (p_mm - origin_mm)).cwiseQuotient(spacing_mm);
}

Eigen::Vector3d Volume::center_mm() const {
  const Eigen::Vector3d mid((dims[0] - 1) * 0.5, (dims[1] - 1) * 0.5, (dims[2] - 1) * 0.5);
  return index_to_physical_mm(mid);
}

std::string validate(const Volume& v) {
  // the dims' product must fit before voxel_count() may be called (dims from a hostile header
  // overflowed it)
  int64_t count = 1;
  for (int a = 0; a < 3; ++a) {
    if (v.dims[a] <= 0) return fmt::format("dims[{}] = {} is not positive", a, v.dims[a]);
    if (count > INT64_MAX / 4 / v.dims[a])
      return fmt::format("dims {}x{}x{} overflow", v.dims[0], v.dims[1], v.dims[2]);
    count *= v.dims[a];
    if (!(v.spacing_mm[a] > 0) || !std::isfinite(v.spacing_mm[a])) {
      return fmt::format("spacing_mm[{}] = {} is not a positive finite number", a, v.spacing_mm[a]);
    }
  }
  if (!v.origin_mm.allFinite()) return "origin_mm is not finite";
  if (!v.direction.allFinite() || std::abs(v.direction.determinant()) < 1e-6) {
    return "direction is not an invertible finite matrix";
  }
  const size_t have = v.type == VoxelType::kInt16 ? v.hu_i16.size() : v.hu_f32.size();
  if (static_cast<int64_t>(have) != v.voxel_count()) {
    return fmt::format("{} voxels of data for dims {}x{}x{}", have, v.dims[0], v.dims[1], v.dims[2]);
  }
  return {};
}

}  // namespace pcisim::anatomy
