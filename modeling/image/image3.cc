#include "modeling/image/image3.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace pcisim::modeling {

ImageGrid ImageGrid::of(const anatomy::Volume& v) {
  return {v.dims, v.spacing_mm, v.origin_mm, v.direction};
}

Eigen::Vector3d ImageGrid::physical_mm(const Eigen::Vector3d& ijk) const {
  return origin_mm + direction * spacing_mm.cwiseProduct(ijk);
}

Eigen::Vector3d ImageGrid::continuous_index(const Eigen::Vector3d& p_mm) const {
  return (direction.inverse() * (p_mm - origin_mm)).cwiseQuotient(spacing_mm);
}

ImageGrid ImageGrid::crop(const std::array<int64_t, 3>& lo, const std::array<int64_t, 3>& d) const {
  ImageGrid g = *this;
  g.dims = d;
  g.origin_mm = physical_mm(Eigen::Vector3d(double(lo[0]), double(lo[1]), double(lo[2])));
  return g;
}

int64_t Mask::count() const {
  return std::count_if(v.begin(), v.end(), [](uint8_t x) { return x != 0; });
}

float FloatImage::at(const Eigen::Vector3d& p, float outside) const {
  const double x = p.x(), y = p.y(), z = p.z();
  if (!(x >= 0 && y >= 0 && z >= 0 && x <= grid.dims[0] - 1 && y <= grid.dims[1] - 1 && z <= grid.dims[2] - 1)) {
    return outside;
  }
  const int64_t i = std::min<int64_t>(int64_t(x), grid.dims[0] - 2 < 0 ? 0 : grid.dims[0] - 2);
  const int64_t j = std::min<int64_t>(int64_t(y), grid.dims[1] - 2 < 0 ? 0 : grid.dims[1] - 2);
  const int64_t k = std::min<int64_t>(int64_t(z), grid.dims[2] - 2 < 0 ? 0 : grid.dims[2] - 2);
  const double fx = x - i, fy = y - j, fz = z - k;
  const int64_t sx = grid.dims[0] > 1 ? 1 : 0, sy = grid.dims[1] > 1 ? grid.dims[0] : 0;
  const int64_t sz = grid.dims[2] > 1 ? grid.dims[0] * grid.dims[1] : 0;
  const float* p0 = v.data() + grid.index(i, j, k);
  const double c00 = p0[0] + fx * (p0[sx] - p0[0]);
  const double c10 = p0[sy] + fx * (p0[sy + sx] - p0[sy]);
  const double c01 = p0[sz] + fx * (p0[sz + sx] - p0[sz]);
  const double c11 = p0[sz + sy] + fx * (p0[sz + sy + sx] - p0[sz + sy]);
  const double c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
  return static_cast<float>(c0 + fz * (c1 - c0));
}

FloatImage crop_hu(const anatomy::Volume& ct, const std::array<int64_t, 3>& lo, const std::array<int64_t, 3>& d) {
  FloatImage f{ImageGrid::of(ct).crop(lo, d), std::vector<float>(d[0] * d[1] * d[2])};
  int64_t n = 0;
  for (int64_t k = 0; k < d[2]; ++k) {
    for (int64_t j = 0; j < d[1]; ++j) {
      const int64_t row = ct.linear_index(lo[0], lo[1] + j, lo[2] + k);
      if (ct.type == anatomy::VoxelType::kInt16) {
        for (int64_t i = 0; i < d[0]; ++i) f.v[n++] = ct.hu_i16[row + i];
      } else {
        for (int64_t i = 0; i < d[0]; ++i) f.v[n++] = ct.hu_f32[row + i];
      }
    }
  }
  return f;
}

void bounding_box(const Mask& m, int64_t margin, std::array<int64_t, 3>* lo, std::array<int64_t, 3>* dims) {
  std::array<int64_t, 3> a{INT64_MAX, INT64_MAX, INT64_MAX}, b{-1, -1, -1};
  const auto& g = m.grid;
  for (int64_t k = 0, n = 0; k < g.dims[2]; ++k) {
    for (int64_t j = 0; j < g.dims[1]; ++j) {
      for (int64_t i = 0; i < g.dims[0]; ++i, ++n) {
        if (!m.v[n]) continue;
        a = {std::min(a[0], i), std::min(a[1], j), std::min(a[2], k)};
        b = {std::max(b[0], i), std::max(b[1], j), std::max(b[2], k)};
      }
    }
  }
  if (b[0] < 0) {
    *lo = {0, 0, 0};
    *dims = {0, 0, 0};
    return;
  }
  for (int ax = 0; ax < 3; ++ax) {
    (*lo)[ax] = std::max<int64_t>(0, a[ax] - margin);
    (*dims)[ax] = std::min<int64_t>(g.dims[ax] - 1, b[ax] + margin) - (*lo)[ax] + 1;
  }
}

Neighbours26::Neighbours26(const Eigen::Vector3d& s) {
  int n = 0;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy && !dz) continue;
        d[n] = {dx, dy, dz};
        length_mm[n] = std::sqrt(dx * dx * s.x() * s.x() + dy * dy * s.y() * s.y() + dz * dz * s.z() * s.z());
        ++n;
      }
    }
  }
}

std::string grid_difference(const ImageGrid& b, const ImageGrid& a) {
  auto dims = [](const ImageGrid& g) {
    return std::to_string(g.dims[0]) + " x " + std::to_string(g.dims[1]) + " x " + std::to_string(g.dims[2]);
  };
  if (b.dims != a.dims) return "dims " + dims(b) + " differ from " + dims(a);
  if (!b.spacing_mm.isApprox(a.spacing_mm, 1e-6)) return "spacing differs";
  if ((b.origin_mm - a.origin_mm).norm() > 1e-6 * a.spacing_mm.minCoeff()) return "origin differs";
  if ((b.direction - a.direction).cwiseAbs().maxCoeff() > 1e-6) return "direction differs";
  return "";
}

}  // namespace pcisim::modeling
