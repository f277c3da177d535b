#include "physics/guidewire/blood_drift.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pcisim::physics {

BloodDrift::BloodDrift(const BloodFlowParams& params, const VesselTree& tree, double grid_m)
    : params_(params), grid_m_(grid_m) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  double r_max = 0.0;
  for (const auto& b : tree.branches)
    for (const auto& p : b.points) {
      lo = lo.cwiseMin(p.position_m);
      hi = hi.cwiseMax(p.position_m);
      r_max = std::max(r_max, p.radius_m);
    }
  if (!(lo.array() <= hi.array()).all()) return;  // empty tree: no flow anywhere
  const double pad = r_max + 2.0 * grid_m_;
  origin_ = lo - Eigen::Vector3d::Constant(pad);
  // keep the grid bounded: coarsen until it has at most 8M cells
  for (;;) {
    for (int k = 0; k < 3; ++k) dims_[k] = static_cast<int>(std::ceil((hi[k] + pad - origin_[k]) / grid_m_)) + 1;
    if (static_cast<double>(dims_.x()) * dims_.y() * dims_.z() <= 8e6) break;
    grid_m_ *= 1.5;
  }
  const size_t cells = static_cast<size_t>(dims_.x()) * dims_.y() * dims_.z();
  velocity_.assign(cells, Eigen::Vector3f::Zero());
  std::vector<float> best(cells, std::numeric_limits<float>::infinity());
  // rasterise every centerline segment: a cell inside the tube takes the flow of its nearest
  // segment, directed proximal to distal
  for (const auto& b : tree.branches) {
    for (size_t k = 0; k + 1 < b.points.size(); ++k) {
      const Eigen::Vector3d a = b.points[k].position_m, c = b.points[k + 1].position_m;
      const Eigen::Vector3d ab = c - a;
      const double len_sq = ab.squaredNorm();
      if (len_sq <= 0.0) continue;
      const Eigen::Vector3f v = (params_.mean_velocity_m_per_s * ab / std::sqrt(len_sq)).cast<float>();
      const double r = std::max(b.points[k].radius_m, b.points[k + 1].radius_m) + grid_m_;
      Eigen::Vector3i i0, i1;
      for (int d = 0; d < 3; ++d) {
        i0[d] = std::clamp(static_cast<int>(std::floor((std::min(a[d], c[d]) - r - origin_[d]) / grid_m_)), 0, dims_[d] - 1);
        i1[d] = std::clamp(static_cast<int>(std::ceil((std::max(a[d], c[d]) + r - origin_[d]) / grid_m_)), 0, dims_[d] - 1);
      }
      for (int z = i0.z(); z <= i1.z(); ++z)
        for (int y = i0.y(); y <= i1.y(); ++y)
          for (int x = i0.x(); x <= i1.x(); ++x) {
            const Eigen::Vector3d p = origin_ + grid_m_ * Eigen::Vector3d(x, y, z);
            const double t = std::clamp((p - a).dot(ab) / len_sq, 0.0, 1.0);
            const double dist = (p - (a + t * ab)).norm();
            const double rad = b.points[k].radius_m + t * (b.points[k + 1].radius_m - b.points[k].radius_m);
            if (dist > rad + grid_m_) continue;
            const size_t idx = (static_cast<size_t>(z) * dims_.y() + y) * dims_.x() + x;
            if (dist < best[idx]) {
              best[idx] = static_cast<float>(dist);
              velocity_[idx] = v;
            }
          }
    }
  }
}

Eigen::Vector3d BloodDrift::velocity(const Eigen::Vector3d& p) const {
  if (velocity_.empty() || !p.allFinite()) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d g = (p - origin_) / grid_m_;
  Eigen::Vector3i i;
  Eigen::Vector3d f;
  for (int k = 0; k < 3; ++k) {
    if (!(g[k] >= 0.0) || g[k] > dims_[k] - 1) return Eigen::Vector3d::Zero();
    i[k] = std::min(static_cast<int>(g[k]), dims_[k] - 2);
    f[k] = g[k] - i[k];
  }
  // eq 12 weights the linked blood cells by distance; trilinear weights are that reading
  // (the printed w_i = d_i / sum d grows with distance, the opposite of its own text)
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const double w = (dx ? f.x() : 1 - f.x()) * (dy ? f.y() : 1 - f.y()) * (dz ? f.z() : 1 - f.z());
    const size_t idx = (static_cast<size_t>(i.z() + dz) * dims_.y() + i.y() + dy) * dims_.x() + i.x() + dx;
    v += w * velocity_[idx].cast<double>();
  }
  return v;
}

void BloodDrift::apply(ChainMailWire& wire, double dt_s) const {
  auto nodes = wire.mutable_nodes_m();
  const double gain = params_.drift_gain * dt_s;
  for (int i = wire.first_free_node(); i < wire.node_count(); ++i) nodes[i] += gain * velocity(nodes[i]);
}

}  // namespace pcisim::physics
