#include "anatomy/volume/gaussian_blur.h"

#include "anatomy/volume/parallel_for.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

namespace pcisim::anatomy {

void gaussian_blur(std::vector<float>* data, const std::array<int64_t, 3>& dims, const Eigen::Vector3d& sigma_vox,
                   int threads) {
  const int64_t nx = dims[0], ny = dims[1], nz = dims[2];
  float* v = data->data();
  for (int axis = 0; axis < 3; ++axis) {
    const double s = sigma_vox[axis];
    if (!(s > 0.05)) continue;
    const int r = static_cast<int>(std::ceil(3.0 * s));
    std::vector<float> w(2 * r + 1);
    double total = 0;
    for (int t = -r; t <= r; ++t) total += w[t + r] = static_cast<float>(std::exp(-0.5 * t * t / (s * s)));
    for (auto& x : w) x = static_cast<float>(x / total);
    if (axis == 0) {
      parallel_for(nz, threads, [&](int64_t k) {
        std::vector<float> row(nx + 2 * r);
        for (int64_t j = 0; j < ny; ++j) {
          float* out = v + nx * (j + ny * k);
          for (int64_t i = 0; i < nx + 2 * r; ++i) row[i] = out[std::clamp<int64_t>(i - r, 0, nx - 1)];
          for (int64_t i = 0; i < nx; ++i) {
            float acc = 0;
            for (int t = 0; t <= 2 * r; ++t) acc += w[t] * row[i + t];
            out[i] = acc;
          }
        }
      });
    } else if (axis == 1) {
      parallel_for(nz, threads, [&](int64_t k) {
        float* slice = v + nx * ny * k;
        std::vector<float> copy(slice, slice + nx * ny);
        for (int64_t j = 0; j < ny; ++j) {
          float* out = slice + nx * j;
          std::fill(out, out + nx, 0.0f);
          for (int t = -r; t <= r; ++t) {
            const float* in = copy.data() + nx * std::clamp<int64_t>(j + t, 0, ny - 1);
            const float wt = w[t + r];
            for (int64_t i = 0; i < nx; ++i) out[i] += wt * in[i];
          }
        }
      });
    } else {
      parallel_for(ny, threads, [&](int64_t j) {
        std::vector<float> plane(nx * nz);
        for (int64_t k = 0; k < nz; ++k) std::copy_n(v + nx * (j + ny * k), nx, plane.data() + nx * k);
        for (int64_t k = 0; k < nz; ++k) {
          float* out = v + nx * (j + ny * k);
          std::fill(out, out + nx, 0.0f);
          for (int t = -r; t <= r; ++t) {
            const float* in = plane.data() + nx * std::clamp<int64_t>(k + t, 0, nz - 1);
            const float wt = w[t + r];
            for (int64_t i = 0; i < nx; ++i) out[i] += wt * in[i];
          }
        }
      });
    }
  }
}

}  // namespace pcisim::anatomy
