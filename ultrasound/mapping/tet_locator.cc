#include "ultrasound/mapping/tet_locator.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pcisim::ultrasound {

void TetLocator::build(const TetSnapshot& mesh) {
  const int nv = static_cast<int>(mesh.rest_mm.cols());
  if (mesh.current_mm.cols() != nv) throw std::invalid_argument("TetSnapshot: rest_mm and current_mm differ in size");
  for (const auto& t : mesh.tets)
    for (int i : t)
      if (i < 0 || i >= nv) throw std::invalid_argument("TetSnapshot: a tet names a vertex out of range");
  tet_count_ = static_cast<int>(mesh.tets.size());
  vertex_count_ = nv;
  inv_current_.assign(tet_count_, Eigen::Matrix3d::Zero());
  v0_current_.assign(tet_count_, Eigen::Vector3d::Zero());
  edges_rest_.resize(tet_count_);
  v0_rest_.resize(tet_count_);
  valid_.assign(tet_count_, 0);
  tet_box_.assign(tet_count_, Eigen::AlignedBox3d());
  for (int t = 0; t < tet_count_; ++t) {
    const auto& v = mesh.tets[t];
    v0_rest_[t] = mesh.rest_mm.col(v[0]);
    for (int k = 0; k < 3; ++k) edges_rest_[t].col(k) = mesh.rest_mm.col(v[k + 1]) - v0_rest_[t];
  }
  // about one tet per cell, the grid's shape following the rest bounding box
  Eigen::AlignedBox3d box;
  for (int i = 0; i < nv; ++i) box.extend(Eigen::Vector3d(mesh.rest_mm.col(i)));
  const Eigen::Vector3d ext = nv > 0 ? Eigen::Vector3d(box.sizes().cwiseMax(1e-9)) : Eigen::Vector3d::Ones();
  const double cell = std::cbrt(ext.prod() / std::max(1, tet_count_));
  for (int k = 0; k < 3; ++k) dims_[k] = std::clamp(static_cast<int>(std::ceil(ext[k] / cell)), 1, 256);
  cell_start_.assign(static_cast<size_t>(dims_.prod()) + 1, 0);
  fill_.assign(static_cast<size_t>(dims_.prod()), 0);
  entries_.clear();
  refit(mesh);
  entries_.reserve(2 * entries_.size() + 16);
}

void TetLocator::refit(const TetSnapshot& mesh) {
  if (mesh.current_mm.cols() != vertex_count_ || static_cast<int>(mesh.tets.size()) != tet_count_)
    throw std::invalid_argument("TetLocator::refit: the snapshot's topology differs from build()");
  Eigen::AlignedBox3d all;
  for (int t = 0; t < tet_count_; ++t) {
    const auto& v = mesh.tets[t];
    const Eigen::Vector3d p0 = mesh.current_mm.col(v[0]);
    Eigen::Matrix3d e;
    Eigen::AlignedBox3d b(p0);
    for (int k = 0; k < 3; ++k) {
      e.col(k) = mesh.current_mm.col(v[k + 1]) - p0;
      b.extend(Eigen::Vector3d(mesh.current_mm.col(v[k + 1])));
    }
    const double det = e.determinant();
    const double scale = e.colwise().norm().prod();
    valid_[t] = std::isfinite(det) && std::abs(det) > 1e-12 * scale && scale > 0.0;
    if (valid_[t]) inv_current_[t] = e.inverse();
    v0_current_[t] = p0;
    tet_box_[t] = b;
    if (valid_[t]) all.extend(b);
  }
  if (all.isEmpty()) all = Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  lo_ = all.min();
  inv_cell_ = dims_.cast<double>().cwiseQuotient(all.sizes().cwiseMax(1e-9));
  const int ncell = dims_.prod();
  auto cell_range = [&](const Eigen::AlignedBox3d& b, Eigen::Vector3i* a, Eigen::Vector3i* z) {
    for (int k = 0; k < 3; ++k) {
      (*a)[k] = std::clamp(static_cast<int>((b.min()[k] - lo_[k]) * inv_cell_[k]), 0, dims_[k] - 1);
      (*z)[k] = std::clamp(static_cast<int>((b.max()[k] - lo_[k]) * inv_cell_[k]), 0, dims_[k] - 1);
    }
  };
  std::fill(fill_.begin(), fill_.end(), 0);
  Eigen::Vector3i a, z;
  for (int t = 0; t < tet_count_; ++t) {
    if (!valid_[t]) continue;
    cell_range(tet_box_[t], &a, &z);
    for (int k = a[2]; k <= z[2]; ++k)
      for (int j = a[1]; j <= z[1]; ++j)
        for (int i = a[0]; i <= z[0]; ++i) ++fill_[i + dims_[0] * (j + dims_[1] * k)];
  }
  cell_start_[0] = 0;
  for (int c = 0; c < ncell; ++c) cell_start_[c + 1] = cell_start_[c] + fill_[c];
  entries_.resize(cell_start_[ncell]);  // within the reserved capacity after build()
  std::copy(cell_start_.begin(), cell_start_.end() - 1, fill_.begin());
  for (int t = 0; t < tet_count_; ++t) {
    if (!valid_[t]) continue;
    cell_range(tet_box_[t], &a, &z);
    for (int k = a[2]; k <= z[2]; ++k)
      for (int j = a[1]; j <= z[1]; ++j)
        for (int i = a[0]; i <= z[0]; ++i) entries_[fill_[i + dims_[0] * (j + dims_[1] * k)]++] = t;
  }
}

LocatorView TetLocator::view() const {
  LocatorView v;
  v.tet_count = tet_count_;
  // (Eigen's fixed-size matrices and vectors are their coefficients, column-major, unpadded)
  static_assert(sizeof(Eigen::Matrix3d) == 9 * sizeof(double) && sizeof(Eigen::Vector3d) == 3 * sizeof(double));
  v.inv_current = inv_current_.empty() ? nullptr : inv_current_[0].data();
  v.v0_current = v0_current_.empty() ? nullptr : v0_current_[0].data();
  v.edges_rest = edges_rest_.empty() ? nullptr : edges_rest_[0].data();
  v.v0_rest = v0_rest_.empty() ? nullptr : v0_rest_[0].data();
  v.valid = valid_.data();
  for (int k = 0; k < 3; ++k) {
    v.dims[k] = dims_[k];
    v.lo[k] = lo_[k];
    v.inv_cell[k] = inv_cell_[k];
  }
  v.cell_start = cell_start_.data();
  v.entries = entries_.data();
  return v;
}

bool TetLocator::to_rest(const Eigen::Vector3d& p, Eigen::Vector3d* rest) const {
  int hint = -1;
  return to_rest(p, rest, &hint);
}

bool TetLocator::to_rest(const Eigen::Vector3d& p, Eigen::Vector3d* rest, int* hint) const {
  const double q[3] = {p.x(), p.y(), p.z()};
  double r[3];
  if (!rest_point(view(), q, r, hint)) return false;
  *rest = Eigen::Vector3d(r[0], r[1], r[2]);
  return true;
}

}  // namespace pcisim::ultrasound
