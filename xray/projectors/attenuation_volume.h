#pragma once
// A CT volume turned into linear attenuation for projection: mu = mu_water (1 + HU/1000) per mm,
// HU below air_below_hu counted as air (mu = 0). Stored as float with a one-voxel zero border
// (so trilinear reads need no bounds checks) plus a coarse grid of per-brick maxima that lets a
// ray skip empty space. Built once per volume; projectors only read it.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "anatomy/volume/volume.h"

namespace pcisim::xray {

struct AttenuationParams {
  double mu_water_per_mm = 0.02;  // water near the effective energy of a fluoroscopy beam
  double air_below_hu = -800;     // lower HU: mu = 0
  int brick_voxels = 8;           // empty-space skipping granularity
};

class AttenuationVolume {
 public:
  AttenuationVolume(const anatomy::Volume& volume, const AttenuationParams& params = {});
  // a volume whose voxel values are mu per mm already, of either sign (a difference of two
  // attenuations: the beating background's per-phase change); bricks skip where |mu| is 0
  static AttenuationVolume from_mu(const anatomy::Volume& mu_per_mm, const AttenuationParams& params = {});

  double mu_of_hu(double hu) const {
    return hu < params_.air_below_hu ? 0.0 : params_.mu_water_per_mm * (1.0 + hu / 1000.0);
  }
  const AttenuationParams& params() const { return params_; }

  // volume voxels (without the border)
  const std::array<int, 3>& dims() const { return dims_; }
  // padded voxels: dims + 2, voxel (i, j, k) of the volume at padded (i+1, j+1, k+1)
  const std::array<int, 3>& padded_dims() const { return padded_; }
  const float* padded_mu() const { return mu_.get(); }
  size_t padded_count() const { return mu_count_; }
  float mu(int i, int j, int k) const {  // volume index, no bounds check
    return mu_[(i + 1) + padded_[0] * ((j + 1) + int64_t(padded_[1]) * (k + 1))];
  }

  // volume index (voxel centres at integers) = index_from_physical * p_mm + index_offset
  const Eigen::Matrix3d& index_from_physical() const { return index_from_physical_; }
  const Eigen::Vector3d& index_offset() const { return index_offset_; }

  // brick (I, J, K) covers padded coordinates [I B, (I+1) B) per axis; its value is the largest
  // |mu| of padded voxels [I B, (I+1) B] (inclusive: a trilinear read there touches them)
  int brick_voxels() const { return params_.brick_voxels; }
  const std::array<int, 3>& brick_dims() const { return brick_dims_; }
  const std::vector<float>& brick_max() const { return brick_max_; }
  // 1 where the brick or one of its 26 neighbours holds some mu: a walk of one ray over it covers
  // every non-empty brick of rays that stay within a brick of it (ray::slice_rays_x8)
  const std::vector<uint8_t>& brick_near() const { return brick_near_; }

  // writing mu in place (the beating background reuses one change volume for every phase): the
  // border must stay zero, and rebuild_bricks() must run before the next projection; a GPU
  // projector's uploaded copy is not updated
  float* mutable_padded_mu() { return mu_.get(); }
  void rebuild_bricks();

 private:
  AttenuationVolume(const anatomy::Volume& volume, const AttenuationParams& params, bool values_are_mu);

  AttenuationParams params_;
  std::array<int, 3> dims_{}, padded_{}, brick_dims_{};
  // 2 MiB aligned, so the kernel may back it with transparent huge pages where THP is "always"
  // (madvise'd huge pages sped the exact traversal ~10 % here but tripled the setup time)
  struct FreeMu {
    void operator()(float* p) const;
  };
  std::unique_ptr<float[], FreeMu> mu_;
  size_t mu_count_ = 0;
  std::vector<float> brick_max_;
  std::vector<uint8_t> brick_near_;
  Eigen::Matrix3d index_from_physical_;
  Eigen::Vector3d index_offset_;
};

}  // namespace pcisim::xray
