#include "xray/projectors/attenuation_volume.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <new>
#include <stdexcept>

namespace pcisim::xray {

void AttenuationVolume::FreeMu::operator()(float* p) const {
  std::free(p);
}

AttenuationVolume::AttenuationVolume(const anatomy::Volume& v, const AttenuationParams& params)
    : AttenuationVolume(v, params, false) {}

AttenuationVolume AttenuationVolume::from_mu(const anatomy::Volume& mu_per_mm, const AttenuationParams& params) {
  return AttenuationVolume(mu_per_mm, params, true);
}

AttenuationVolume::AttenuationVolume(const anatomy::Volume& v, const AttenuationParams& params, bool values_are_mu)
    : params_(params) {
  if (const std::string bad = validate(v); !bad.empty()) throw std::invalid_argument("AttenuationVolume: " + bad);
  if (params.brick_voxels < 1) throw std::invalid_argument("AttenuationVolume: brick_voxels must be >= 1");
  for (int a = 0; a < 3; ++a) {
    dims_[a] = static_cast<int>(v.dims[a]);
    padded_[a] = dims_[a] + 2;
  }
  mu_count_ = size_t(padded_[0]) * padded_[1] * padded_[2];
  {
    constexpr size_t kHuge = size_t(2) << 20;
    const size_t bytes = (mu_count_ * sizeof(float) + kHuge - 1) / kHuge * kHuge;
    void* p = std::aligned_alloc(kHuge, bytes);
    if (!p) throw std::bad_alloc();
    mu_.reset(static_cast<float*>(p));
    std::fill(mu_.get(), mu_.get() + mu_count_, 0.0f);
  }
  for (int k = 0; k < dims_[2]; ++k) {
    for (int j = 0; j < dims_[1]; ++j) {
      float* row = mu_.get() + 1 + padded_[0] * ((j + 1) + int64_t(padded_[1]) * (k + 1));
      for (int i = 0; i < dims_[0]; ++i) {
        row[i] = values_are_mu ? v.hu(i, j, k) : static_cast<float>(mu_of_hu(v.hu(i, j, k)));
      }
    }
  }
  // physical -> index: p = origin + D diag(s) idx  =>  idx = diag(1/s) D^-1 (p - origin)
  index_from_physical_ = v.spacing_mm.cwiseInverse().asDiagonal() * v.direction.inverse();
  index_offset_ = -index_from_physical_ * v.origin_mm;

  rebuild_bricks();
}

void AttenuationVolume::rebuild_bricks() {
  const int b = params_.brick_voxels;
  for (int a = 0; a < 3; ++a) brick_dims_[a] = (padded_[a] - 1) / b + 1;
  brick_max_.assign(int64_t(brick_dims_[0]) * brick_dims_[1] * brick_dims_[2], 0.0f);
  for (int bk = 0; bk < brick_dims_[2]; ++bk) {
    for (int bj = 0; bj < brick_dims_[1]; ++bj) {
      for (int bi = 0; bi < brick_dims_[0]; ++bi) {
        float m = 0.0f;
        for (int k = bk * b; k <= std::min((bk + 1) * b, padded_[2] - 1); ++k) {
          for (int j = bj * b; j <= std::min((bj + 1) * b, padded_[1] - 1); ++j) {
            const float* row = mu_.get() + padded_[0] * (j + int64_t(padded_[1]) * k);
            for (int i = bi * b; i <= std::min((bi + 1) * b, padded_[0] - 1); ++i) m = std::max(m, std::abs(row[i]));
          }
        }
        brick_max_[bi + brick_dims_[0] * (bj + int64_t(brick_dims_[1]) * bk)] = m;
      }
    }
  }
  // the same dilated by one brick
  const auto& n = brick_dims_;
  brick_near_.assign(brick_max_.size(), 0);
  for (int bk = 0; bk < n[2]; ++bk)
    for (int bj = 0; bj < n[1]; ++bj)
      for (int bi = 0; bi < n[0]; ++bi) {
        if (!(brick_max_[bi + n[0] * (bj + int64_t(n[1]) * bk)] > 0.0f)) continue;
        for (int k = std::max(bk - 1, 0); k <= std::min(bk + 1, n[2] - 1); ++k)
          for (int j = std::max(bj - 1, 0); j <= std::min(bj + 1, n[1] - 1); ++j)
            for (int i = std::max(bi - 1, 0); i <= std::min(bi + 1, n[0] - 1); ++i)
              brick_near_[i + n[0] * (j + int64_t(n[1]) * k)] = 1;
      }
}

}  // namespace pcisim::xray
