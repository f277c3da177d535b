#include "modeling/image/vesselness.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "anatomy/volume/gaussian_blur.h"
#include "anatomy/volume/parallel_for.h"

namespace pcisim::modeling {

std::array<double, 3> symmetric_eigenvalues_by_magnitude(double a, double b, double c, double d, double e, double f) {
  std::array<double, 3> l;
  const double off = d * d + e * e + f * f;
  if (off <= 1e-30 * (a * a + b * b + c * c) || off == 0) {
    l = {a, b, c};
  } else {
    // A = q I + p B with q the mean of the diagonal; the eigenvalues of B are 2 cos(phi + 2 pi k / 3)
    const double q = (a + b + c) / 3;
    const double p2 = (a - q) * (a - q) + (b - q) * (b - q) + (c - q) * (c - q) + 2 * off;
    const double p = std::sqrt(p2 / 6);
    const double ba = (a - q) / p, bb = (b - q) / p, bc = (c - q) / p, bd = d / p, be = e / p, bf = f / p;
    const double det = ba * (bb * bc - bf * bf) - bd * (bd * bc - bf * be) + be * (bd * bf - bb * be);
    const double phi = std::acos(std::clamp(det / 2, -1.0, 1.0)) / 3;
    l[0] = q + 2 * p * std::cos(phi);
    l[2] = q + 2 * p * std::cos(phi + 2 * M_PI / 3);
    l[1] = 3 * q - l[0] - l[2];
  }
  std::sort(l.begin(), l.end(), [](double x, double y) { return std::abs(x) < std::abs(y); });
  return l;
}

FloatImage bright_tube_vesselness(const FloatImage& image, const Mask* where, const VesselnessOptions& o) {
  const ImageGrid& g = image.grid;
  if (static_cast<int64_t>(image.v.size()) != g.size() || (where && where->v.size() != image.v.size()))
    throw std::invalid_argument(
        "bright_tube_vesselness: the image and the mask must hold one value per voxel of the grid");
  FloatImage out{g, std::vector<float>(image.v.size(), 0.0f)};
  const int steps = std::max(1, o.sigma_steps);
  const Eigen::Vector3d h = g.spacing_mm;
  std::vector<float> smooth;
  for (int s = 0; s < steps; ++s) {
    const double sigma =
        steps == 1 ? o.sigma_min_mm : o.sigma_min_mm + (o.sigma_max_mm - o.sigma_min_mm) * s / double(steps - 1);
    smooth = image.v;
    anatomy::gaussian_blur(&smooth, g.dims, Eigen::Vector3d::Constant(sigma).cwiseQuotient(h), std::max(1, o.threads));
    const double norm = sigma * sigma;
    // one z slice a work item; the outermost voxels (no central difference) stay 0
    anatomy::parallel_for(g.dims[2], std::max(1, o.threads), [&](int64_t k) {
      if (k < 1 || k + 1 >= g.dims[2]) return;
      const int64_t sx = 1, sy = g.dims[0], sz = g.dims[0] * g.dims[1];
      for (int64_t j = 1; j + 1 < g.dims[1]; ++j) {
        for (int64_t i = 1; i + 1 < g.dims[0]; ++i) {
          const int64_t n = g.index(i, j, k);
          if (where && !where->v[n]) continue;
          const float* f = smooth.data() + n;
          auto at = [&](int64_t off) { return double(f[off]); };
          const double c0 = at(0);
          // the Hessian (mm^-2) by central differences, scale-normalised
          const double xx = (at(sx) - 2 * c0 + at(-sx)) / (h.x() * h.x()) * norm;
          const double yy = (at(sy) - 2 * c0 + at(-sy)) / (h.y() * h.y()) * norm;
          const double zz = (at(sz) - 2 * c0 + at(-sz)) / (h.z() * h.z()) * norm;
          const double xy = (at(sx + sy) - at(sx - sy) - at(-sx + sy) + at(-sx - sy)) / (4 * h.x() * h.y()) * norm;
          const double xz = (at(sx + sz) - at(sx - sz) - at(-sx + sz) + at(-sx - sz)) / (4 * h.x() * h.z()) * norm;
          const double yz = (at(sy + sz) - at(sy - sz) - at(-sy + sz) + at(-sy - sz)) / (4 * h.y() * h.z()) * norm;
          const auto l = symmetric_eigenvalues_by_magnitude(xx, yy, zz, xy, xz, yz);
          // [Frangi eq 15, bright objects]: both cross-sectional eigenvalues negative
          if (l[1] >= 0 || l[2] >= 0) continue;
          const double ra = std::abs(l[1]) / std::abs(l[2]);
          const double rb = std::abs(l[0]) / std::sqrt(std::abs(l[1] * l[2]));
          const double s2 = l[0] * l[0] + l[1] * l[1] + l[2] * l[2];
          const double v = (1 - std::exp(-ra * ra / (2 * o.alpha * o.alpha))) *
                           std::exp(-rb * rb / (2 * o.beta * o.beta)) * (1 - std::exp(-s2 / (2 * o.gamma * o.gamma)));
          out.v[n] = std::max(out.v[n], static_cast<float>(v));
        }
      }
    });
  }
  return out;
}

}  // namespace pcisim::modeling
