#include "xray/fluoro/heart_warp.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include "xray/projectors/ray_march.h"
#include "xray/projectors/views.h"

namespace pcisim::xray {

std::string validate(const BeatSamples& s) {
  if (s.bins() < 2) return "beat samples: " + std::to_string(s.bins()) + " phase bins, at least 2 needed";
  if (s.rest_mm.empty()) return "beat samples: no points";
  // finite, and within a kilometre: the casts to voxel and bucket indices stay defined
  auto sane = [](const Eigen::Vector3d& p) { return p.allFinite() && p.cwiseAbs().maxCoeff() < 1e6; };
  for (const auto& p : s.rest_mm)
    if (!sane(p)) return "beat samples: a rest point is not finite or lies over 1 km away";
  for (int b = 0; b < s.bins(); ++b) {
    if (s.at_bin_mm[b].size() != s.rest_mm.size())
      return "beat samples: bin " + std::to_string(b) + " has " + std::to_string(s.at_bin_mm[b].size()) +
             " points, rest has " + std::to_string(s.rest_mm.size());
    for (const auto& p : s.at_bin_mm[b])
      if (!sane(p))
        return "beat samples: a point of bin " + std::to_string(b) + " is not finite or lies over 1 km away";
  }
  return {};
}

BeatSamples beat_samples_from_m(const Eigen::Matrix3Xd& rest_m, const std::vector<Eigen::Matrix3Xd>& at_bin_m) {
  BeatSamples s;
  s.rest_mm.reserve(rest_m.cols());
  for (Eigen::Index i = 0; i < rest_m.cols(); ++i) s.rest_mm.push_back(1000.0 * rest_m.col(i));
  for (const Eigen::Matrix3Xd& bin : at_bin_m) {
    s.at_bin_mm.emplace_back();
    s.at_bin_mm.back().reserve(bin.cols());
    for (Eigen::Index i = 0; i < bin.cols(); ++i) s.at_bin_mm.back().push_back(1000.0 * bin.col(i));
  }
  return s;
}

BeatSamples every_kth_bin(const BeatSamples& s, int k) {
  if (k < 1 || s.bins() % k != 0 || s.bins() / k < 2)
    throw std::invalid_argument("every_kth_bin: " + std::to_string(s.bins()) + " bins cannot be taken every " +
                                std::to_string(k));
  BeatSamples out;
  out.rest_mm = s.rest_mm;
  for (int b = 0; b < s.bins(); b += k) out.at_bin_mm.push_back(s.at_bin_mm[b]);
  return out;
}

std::string validate(const HeartWarpParams& p) {
  if (!(p.kernel_mm > 0 && p.kernel_mm <= 50)) return "kernel_mm must be in (0, 50]";
  if (!(p.reach_mm > p.kernel_mm && p.reach_mm <= 100)) return "reach_mm must be in (kernel_mm, 100]";
  if (!(p.grid_mm > 0 && p.grid_mm <= 20)) return "grid_mm must be in (0, 20]";
  if (p.inverse_iterations < 0 || p.inverse_iterations > 20) return "inverse_iterations must be in [0, 20]";
  return {};
}

namespace {

// 1 up to `inner`, 0 from `outer`, smooth between
double fade(double r, double inner, double outer) {
  if (r <= inner) return 1.0;
  if (r >= outer) return 0.0;
  const double s = (outer - r) / (outer - inner);
  return s * s * (3.0 - 2.0 * s);
}

}  // namespace

HeartWarp::HeartWarp(const AttenuationVolume& ct, const BeatSamples& samples, const HeartWarpParams& params)
    : ct_(ct), params_(params), bins_(samples.bins()), index_from_physical_(ct.index_from_physical()) {
  if (const std::string bad = validate(samples); !bad.empty()) throw std::invalid_argument("HeartWarp: " + bad);
  if (const std::string bad = validate(params); !bad.empty()) throw std::invalid_argument("HeartWarp: " + bad);
  const Eigen::Matrix3d& a = index_from_physical_;
  const Eigen::Vector3d& b = ct.index_offset();
  const Eigen::Matrix3d physical_from_index = a.inverse();
  const size_t n = samples.rest_mm.size();

  // the box: every sample at rest and moved, plus the reach, in voxels, clipped to the CT
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  auto grow = [&](const Eigen::Vector3d& p_mm) {
    const Eigen::Vector3d ijk = a * p_mm + b;
    lo = lo.cwiseMin(ijk);
    hi = hi.cwiseMax(ijk);
  };
  for (size_t i = 0; i < n; ++i) {
    grow(samples.rest_mm[i]);
    for (int bin = 0; bin < bins_; ++bin) grow(samples.at_bin_mm[bin][i]);
  }
  for (int c = 0; c < 3; ++c) {
    const double margin = params.reach_mm / physical_from_index.col(c).norm() + 1;
    box_lo_[c] = std::max(0, static_cast<int>(std::floor(lo[c] - margin)));
    box_hi_[c] = std::min(ct.dims()[c], static_cast<int>(std::ceil(hi[c] + margin)) + 1);
    if (box_lo_[c] >= box_hi_[c]) throw std::invalid_argument("HeartWarp: the heart's samples lie outside the CT");
  }
  for (int c = 0; c < 3; ++c) {
    stride_[c] = std::max(1, static_cast<int>(std::lround(params.grid_mm / physical_from_index.col(c).norm())));
    nodes_[c] = (box_hi_[c] - 1 - box_lo_[c]) / stride_[c] + 2;
  }
  const size_t node_count = size_t(nodes_[0]) * nodes_[1] * nodes_[2];

  // samples bucketed by rest position in cells of the reach (mm)
  const double cell = params.reach_mm;
  auto key = [&](const Eigen::Vector3d& p) {
    const int64_t x = static_cast<int64_t>(std::floor(p[0] / cell)) & 0x1fffff;
    const int64_t y = static_cast<int64_t>(std::floor(p[1] / cell)) & 0x1fffff;
    const int64_t z = static_cast<int64_t>(std::floor(p[2] / cell)) & 0x1fffff;
    return (x << 42) | (y << 21) | z;
  };
  std::unordered_map<int64_t, std::vector<int>> buckets;
  for (size_t i = 0; i < n; ++i) buckets[key(samples.rest_mm[i])].push_back(static_cast<int>(i));
  // displacements in voxel units, bin-major per sample: d[i * bins + bin]
  std::vector<Eigen::Vector3f> d(n * bins_);
  for (size_t i = 0; i < n; ++i)
    for (int bin = 0; bin < bins_; ++bin)
      d[i * bins_ + bin] = (a * (samples.at_bin_mm[bin][i] - samples.rest_mm[i])).cast<float>();

  // forward field at each node: the Gaussian blend of the samples within reach, faded by the
  // distance to the nearest one (u = sum w d / sum w, w = exp(-r^2 / 2 sigma^2))
  forward_.assign(bins_, std::vector<Eigen::Vector3f>(node_count, Eigen::Vector3f::Zero()));
  const Eigen::Vector3d origin_mm = -physical_from_index * b;
  const double inv_two_sigma2 = 1.0 / (2.0 * params.kernel_mm * params.kernel_mm);
  const double reach2 = params.reach_mm * params.reach_mm;
  std::vector<Eigen::Vector3d> acc(bins_);
  for (int k = 0; k < nodes_[2]; ++k) {
    for (int j = 0; j < nodes_[1]; ++j) {
      for (int i = 0; i < nodes_[0]; ++i) {
        const Eigen::Vector3d ijk(box_lo_[0] + stride_[0] * i, box_lo_[1] + stride_[1] * j,
                                  box_lo_[2] + stride_[2] * k);
        const Eigen::Vector3d x = origin_mm + physical_from_index * ijk;
        std::fill(acc.begin(), acc.end(), Eigen::Vector3d::Zero());
        double w_sum = 0, r2_min = reach2;
        const Eigen::Vector3d c0 = (x / cell).array().floor();
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const auto it = buckets.find(key((c0 + Eigen::Vector3d(dx + 0.5, dy + 0.5, dz + 0.5)) * cell));
              if (it == buckets.end()) continue;
              for (const int s : it->second) {
                const double r2 = (samples.rest_mm[s] - x).squaredNorm();
                if (r2 >= reach2) continue;
                const double w = std::exp(-r2 * inv_two_sigma2);
                w_sum += w;
                r2_min = std::min(r2_min, r2);
                for (int bin = 0; bin < bins_; ++bin) acc[bin] += w * d[size_t(s) * bins_ + bin].cast<double>();
              }
            }
        if (!(w_sum > 0)) continue;
        const double f = fade(std::sqrt(r2_min), params.kernel_mm, params.reach_mm) / w_sum;
        const size_t node = i + size_t(nodes_[0]) * (j + size_t(nodes_[1]) * k);
        for (int bin = 0; bin < bins_; ++bin) forward_[bin][node] = (f * acc[bin]).cast<float>();
      }
    }
  }

  // inverse by fixed point: v(x) = u(x - v(x)), starting from v = u(x)
  inverse_ = forward_;
  const Eigen::Vector3f lattice_step(stride_[0], stride_[1], stride_[2]);  // voxels per lattice step
  for (int bin = 0; bin < bins_; ++bin) {
    std::vector<Eigen::Vector3f>& v = inverse_[bin];
    for (int it = 0; it < params.inverse_iterations; ++it) {
      for (int k = 0; k < nodes_[2]; ++k)
        for (int j = 0; j < nodes_[1]; ++j)
          for (int i = 0; i < nodes_[0]; ++i) {
            const size_t node = i + size_t(nodes_[0]) * (j + size_t(nodes_[1]) * k);
            const Eigen::Vector3f at = Eigen::Vector3f(i, j, k) - v[node].cwiseQuotient(lattice_step);
            v[node] = field_at(forward_[bin], at);
          }
    }
  }
}

// trilinear on the lattice (node coordinates), clamped to it
Eigen::Vector3f HeartWarp::field_at(const std::vector<Eigen::Vector3f>& field, const Eigen::Vector3f& node) const {
  int i0[3];
  float f[3];
  for (int c = 0; c < 3; ++c) {
    const float x = std::clamp(node[c], 0.0f, float(nodes_[c] - 1));
    i0[c] = std::min(static_cast<int>(x), nodes_[c] - 2);
    f[c] = x - i0[c];
  }
  const size_t sy = nodes_[0], sz = size_t(nodes_[0]) * nodes_[1];
  const Eigen::Vector3f* p = field.data() + i0[0] + sy * i0[1] + sz * i0[2];
  const Eigen::Vector3f c00 = p[0] + f[0] * (p[1] - p[0]);
  const Eigen::Vector3f c10 = p[sy] + f[0] * (p[sy + 1] - p[sy]);
  const Eigen::Vector3f c01 = p[sz] + f[0] * (p[sz + 1] - p[sz]);
  const Eigen::Vector3f c11 = p[sz + sy] + f[0] * (p[sz + sy + 1] - p[sz + sy]);
  const Eigen::Vector3f c0 = c00 + f[1] * (c10 - c00), c1 = c01 + f[1] * (c11 - c01);
  return c0 + f[2] * (c1 - c0);
}

Eigen::Vector3d HeartWarp::displacement_mm(int bin, const Eigen::Vector3d& rest_mm) const {
  const Eigen::Vector3d ijk = index_from_physical_ * rest_mm + ct_.index_offset();
  for (int c = 0; c < 3; ++c)
    if (!(ijk[c] >= box_lo_[c] && ijk[c] <= box_hi_[c] - 1)) return Eigen::Vector3d::Zero();
  const Eigen::Vector3f node = (ijk - Eigen::Vector3d(box_lo_[0], box_lo_[1], box_lo_[2]))
                                   .cwiseQuotient(Eigen::Vector3d(stride_[0], stride_[1], stride_[2]))
                                   .cast<float>();
  const Eigen::Vector3d u_voxels = field_at(forward_.at(bin), node).cast<double>();
  return index_from_physical_.inverse() * u_voxels;
}

AttenuationVolume HeartWarp::make_change_volume() const {
  // the box's own volume: index = CT index - box_lo, same affine otherwise
  anatomy::Volume v;
  for (int c = 0; c < 3; ++c) v.dims[c] = box_hi_[c] - box_lo_[c];
  v.spacing_mm = Eigen::Vector3d::Ones();
  v.direction = index_from_physical_.inverse();
  v.origin_mm = v.direction * (Eigen::Vector3d(box_lo_[0], box_lo_[1], box_lo_[2]) - ct_.index_offset());
  v.type = anatomy::VoxelType::kFloat32;
  v.hu_f32.assign(v.voxel_count(), 0.0f);
  return AttenuationVolume::from_mu(v, ct_.params());
}

// mu(x - v_b(x)) over the box into `out`: the change volume (minus the static mu; box voxel
// (i, j, k) at padded (i - lo + 1, ...)) or a copy of the whole CT (at padded (i + 1, ...))
void HeartWarp::write_box(int bin, AttenuationVolume* out, bool minus_static) const {
  const std::array<int, 3>& pd = out->padded_dims();
  const ray::GridView g = grid_view(ct_);
  const std::vector<Eigen::Vector3f>& v = inverse_.at(bin);
  float* mu = out->mutable_padded_mu();
  const Eigen::Vector3f inv_stride(1.0f / stride_[0], 1.0f / stride_[1], 1.0f / stride_[2]);
  for (int k = box_lo_[2]; k < box_hi_[2]; ++k) {
    for (int j = box_lo_[1]; j < box_hi_[1]; ++j) {
      const int64_t row_j = minus_static ? (j - box_lo_[1] + 1) : (j + 1);
      const int64_t row_k = minus_static ? (k - box_lo_[2] + 1) : (k + 1);
      float* row = mu + pd[0] * (row_j + int64_t(pd[1]) * row_k) + (minus_static ? 1 - box_lo_[0] : 1);
      for (int i = box_lo_[0]; i < box_hi_[0]; ++i) {
        const Eigen::Vector3f node((i - box_lo_[0]) * inv_stride[0], (j - box_lo_[1]) * inv_stride[1],
                                   (k - box_lo_[2]) * inv_stride[2]);
        const Eigen::Vector3f s = field_at(v, node);
        // padded coordinates are volume index + 1
        const float moved = ray::trilinear(g, i + 1 - s[0], j + 1 - s[1], k + 1 - s[2]);
        row[i] = minus_static ? moved - ct_.mu(i, j, k) : moved;
      }
    }
  }
  out->rebuild_bricks();
}

void HeartWarp::write_change(int bin, AttenuationVolume* change) const {
  const std::array<int, 3>& pd = change->padded_dims();
  if (pd[0] != box_hi_[0] - box_lo_[0] + 2 || pd[1] != box_hi_[1] - box_lo_[1] + 2 ||
      pd[2] != box_hi_[2] - box_lo_[2] + 2)
    throw std::invalid_argument("HeartWarp::write_change: the change volume is not this warp's box");
  write_box(bin, change, true);
}

void HeartWarp::write_warped(int bin, AttenuationVolume* ct_copy) const {
  if (ct_copy->dims() != ct_.dims())
    throw std::invalid_argument("HeartWarp::write_warped: the volume is not the size of this warp's CT");
  write_box(bin, ct_copy, false);
}

}  // namespace pcisim::xray
