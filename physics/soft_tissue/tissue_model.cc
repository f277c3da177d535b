#include "physics/soft_tissue/tissue_model.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "anatomy/mesh/kuhn_tetrahedra.h"
#include "physics/pbd/grid_clusters.h"
#include "physics/sdf/sdf_kernels.h"

namespace pcisim::physics::soft_tissue {

using Eigen::Matrix3d;
using Eigen::Matrix3Xd;
using Eigen::Vector3d;

namespace {

std::string mm(double m) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", m * 1e3);
  return buf;
}

// [soft-tissue "Collision and data preparation"] voxelisation of the closed mesh: a voxel is
// occupied when its centre is inside. Inside = parity of the crossings of the +z ray through the
// centre's column; the grid is shifted by a small irrational fraction of a voxel so that no column
// passes exactly through a vertex or an edge of a symmetric mesh.
Matrix3Xd voxelise(const anatomy::TriangleMesh& mesh, double h) {
  Vector3d lo = Vector3d::Constant(1e300), hi = Vector3d::Constant(-1e300);
  for (const Vector3d& v : mesh.vertices_m) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Vector3d origin = lo + h * Vector3d(0.5 + 0.0123456789, 0.5 + 0.0314159265, 0.5);
  const int nx = static_cast<int>(std::ceil((hi.x() - origin.x()) / h)) + 1;
  const int ny = static_cast<int>(std::ceil((hi.y() - origin.y()) / h)) + 1;
  std::vector<std::vector<int>> column(static_cast<size_t>(nx) * ny);
  for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t) {
    Vector3d tlo = Vector3d::Constant(1e300), thi = Vector3d::Constant(-1e300);
    for (int v : mesh.triangles[t]) {
      tlo = tlo.cwiseMin(mesh.vertices_m[v]);
      thi = thi.cwiseMax(mesh.vertices_m[v]);
    }
    const int i0 = std::max(0, static_cast<int>(std::ceil((tlo.x() - origin.x()) / h)));
    const int i1 = std::min(nx - 1, static_cast<int>(std::floor((thi.x() - origin.x()) / h)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((tlo.y() - origin.y()) / h)));
    const int j1 = std::min(ny - 1, static_cast<int>(std::floor((thi.y() - origin.y()) / h)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) column[static_cast<size_t>(j) * nx + i].push_back(t);
  }
  std::vector<Vector3d> inside;
  std::vector<double> z;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double px = origin.x() + i * h, py = origin.y() + j * h;
      z.clear();
      for (int t : column[static_cast<size_t>(j) * nx + i]) {
        const Vector3d& a = mesh.vertices_m[mesh.triangles[t][0]];
        const Vector3d& b = mesh.vertices_m[mesh.triangles[t][1]];
        const Vector3d& c = mesh.vertices_m[mesh.triangles[t][2]];
        // barycentric coordinates of (px, py) in the triangle's xy projection
        const double d = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
        if (d == 0.0) continue;
        const double wb = ((px - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (py - a.y())) / d;
        const double wc = ((b.x() - a.x()) * (py - a.y()) - (px - a.x()) * (b.y() - a.y())) / d;
        const double wa = 1.0 - wb - wc;
        if (wa < 0.0 || wb < 0.0 || wc < 0.0) continue;
        z.push_back(wa * a.z() + wb * b.z() + wc * c.z());
      }
      std::sort(z.begin(), z.end());
      for (size_t q = 0; q + 1 < z.size(); q += 2) {
        const int k0 = static_cast<int>(std::ceil((z[q] - origin.z()) / h));
        const int k1 = static_cast<int>(std::floor((z[q + 1] - origin.z()) / h));
        for (int k = k0; k <= k1; ++k) inside.emplace_back(px, py, origin.z() + k * h);
      }
    }
  Matrix3Xd out(3, static_cast<Eigen::Index>(inside.size()));
  for (size_t n = 0; n < inside.size(); ++n) out.col(static_cast<Eigen::Index>(n)) = inside[n];
  return out;
}

// [soft-tissue "Collision and data preparation"] greedy removal: the samples are visited in
// voxel order; the first remaining one becomes a particle and every sample closer than the radius
// to it is removed. Equivalently a sample is kept iff no particle kept before it lies closer than
// r, so particles are >= r apart and every sample lies within < r of a particle.
Matrix3Xd greedy_sample(const Matrix3Xd& samples, double r) {
  auto key = [r](const Vector3d& p, int di, int dj, int dk) {
    const int64_t i = static_cast<int64_t>(std::floor(p.x() / r)) + di;
    const int64_t j = static_cast<int64_t>(std::floor(p.y() / r)) + dj;
    const int64_t k = static_cast<int64_t>(std::floor(p.z() / r)) + dk;
    return (i & 0x1fffff) | ((j & 0x1fffff) << 21) | ((k & 0x1fffff) << 42);
  };
  std::unordered_map<int64_t, std::vector<int>> cells;
  std::vector<int> kept;
  const double r2 = r * r;
  for (Eigen::Index n = 0; n < samples.cols(); ++n) {
    const Vector3d p = samples.col(n);
    bool removed = false;
    for (int dk = -1; dk <= 1 && !removed; ++dk)
      for (int dj = -1; dj <= 1 && !removed; ++dj)
        for (int di = -1; di <= 1 && !removed; ++di) {
          const auto it = cells.find(key(p, di, dj, dk));
          if (it == cells.end()) continue;
          for (int q : it->second)
            if ((samples.col(q) - p).squaredNorm() < r2) {
              removed = true;
              break;
            }
        }
    if (removed) continue;
    kept.push_back(static_cast<int>(n));
    cells[key(p, 0, 0, 0)].push_back(static_cast<int>(n));
  }
  Matrix3Xd out(3, static_cast<Eigen::Index>(kept.size()));
  for (size_t n = 0; n < kept.size(); ++n) out.col(static_cast<Eigen::Index>(n)) = samples.col(kept[n]);
  return out;
}

// [soft-tissue "Weighted matrix blending"] up to four nearest cluster frames (distance from the
// point to the cluster's rest centre), weights 1/d^2 normalised to sum 1; a point on a centre
// (d < 1e-12 m) takes that frame alone.
SkinBinding bind(const Vector3d& p, const Matrix3Xd& centres) {
  const int n = static_cast<int>(centres.cols());
  std::vector<std::pair<double, int>> d2(static_cast<size_t>(n));
  for (int c = 0; c < n; ++c) d2[c] = {(centres.col(c) - p).squaredNorm(), c};
  const int k = std::min(kMaxSkinClusters, n);
  std::partial_sort(d2.begin(), d2.begin() + k, d2.end());
  SkinBinding b;
  if (d2[0].first < 1e-24) {
    b.count = 1;
    b.cluster[0] = d2[0].second;
    b.weight[0] = 1.0;
  } else {
    b.count = k;
    double sum = 0.0;
    for (int q = 0; q < k; ++q) {
      b.cluster[q] = d2[q].second;
      b.weight[q] = 1.0 / d2[q].first;
      sum += b.weight[q];
    }
    for (int q = 0; q < k; ++q) b.weight[q] /= sum;
  }
  for (int q = 0; q < b.count; ++q) b.local_m[q] = p - centres.col(b.cluster[q]);
  return b;
}

// barycentric coordinates of p in tetrahedron (a, b, c, d)
Eigen::Vector4d barycentric(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c,
                            const Vector3d& d) {
  Matrix3d m;
  m << b - a, c - a, d - a;
  const Vector3d w = m.inverse() * (p - a);
  return {1.0 - w.sum(), w.x(), w.y(), w.z()};
}

// [soft-tissue "Weighted matrix blending", last paragraph] a coarse tetrahedral mesh over the
// particles: cubes of edge h over the particles' box, six tetrahedra per cube around the diagonal
// 0-7 (corner c = x + 2y + 4z), kept when some particle lies in it
void build_tets(TissueModel& model, double h) {
  const Vector3d lo = model.rest_m.rowwise().minCoeff().array() - 0.5 * h;
  const Vector3d hi = model.rest_m.rowwise().maxCoeff().array() + 0.5 * h;
  const Eigen::Array3i n = ((hi - lo) / h).array().ceil().cast<int>().max(1);
  auto vid = [&](int i, int j, int k) { return i + (n.x() + 1) * (j + (n.y() + 1) * k); };
  auto vpos = [&](int v) {
    const int i = v % (n.x() + 1), j = (v / (n.x() + 1)) % (n.y() + 1), k = v / ((n.x() + 1) * (n.y() + 1));
    return Vector3d(lo + h * Vector3d(i, j, k));
  };
  std::vector<std::array<int, 4>> kept;
  std::vector<char> used(static_cast<size_t>((n.x() + 1) * (n.y() + 1) * (n.z() + 1)), 0);
  std::vector<std::vector<int>> in_cube(static_cast<size_t>(n.prod()));
  for (Eigen::Index p = 0; p < model.rest_m.cols(); ++p) {
    const Eigen::Array3i c = ((model.rest_m.col(p) - lo) / h).array().floor().cast<int>().min(n - 1).max(0);
    in_cube[c.x() + n.x() * (c.y() + n.y() * c.z())].push_back(static_cast<int>(p));
  }
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i) {
        const auto& members = in_cube[i + n.x() * (j + n.y() * k)];
        if (members.empty()) continue;
        int corner[8];
        for (int q = 0; q < 8; ++q) corner[q] = vid(i + (q & 1), j + ((q >> 1) & 1), k + ((q >> 2) & 1));
        for (const auto& t : anatomy::kKuhnTetrahedra) {
          const std::array<int, 4> tet{corner[t[0]], corner[t[1]], corner[t[2]], corner[t[3]]};
          bool holds = false;
          for (int p : members)
            holds =
                holds ||
                barycentric(model.rest_m.col(p), vpos(tet[0]), vpos(tet[1]), vpos(tet[2]), vpos(tet[3])).minCoeff() >=
                    -1e-12;
          if (!holds) continue;
          kept.push_back(tet);
          for (int v : tet) used[v] = 1;
        }
      }
  std::vector<int> remap(used.size(), -1);
  int count = 0;
  for (size_t v = 0; v < used.size(); ++v)
    if (used[v]) remap[v] = count++;
  model.tet_vertices_m.resize(3, count);
  for (size_t v = 0; v < used.size(); ++v)
    if (used[v]) model.tet_vertices_m.col(remap[v]) = vpos(static_cast<int>(v));
  model.tets.clear();
  for (const auto& t : kept) model.tets.push_back({remap[t[0]], remap[t[1]], remap[t[2]], remap[t[3]]});
}

// each point's distance to the surface, up to max_m: the points binned in cubes of max_m, each
// triangle tested against the points in the cubes its box (grown by max_m) overlaps
Eigen::VectorXd skin_depths(const anatomy::TriangleMesh& mesh, const Matrix3Xd& x_m, double max_m) {
  Eigen::VectorXd depth = Eigen::VectorXd::Constant(x_m.cols(), max_m);
  if (x_m.cols() == 0) return depth;
  const Vector3d lo = x_m.rowwise().minCoeff().array() - max_m;
  const Eigen::Vector3i n = ((x_m.rowwise().maxCoeff() - lo).array() / max_m).floor().cast<int>() + 2;
  // clamped before the cast: a far (or non-finite) point lands in an edge cell, never past it
  auto cell = [&](const Vector3d& p) {
    const Eigen::Array3d c = ((p - lo) / max_m).array().floor();
    return c.max(0.0).min((n.array() - 1).cast<double>()).cast<int>().matrix().eval();
  };
  std::vector<std::vector<int>> bin(static_cast<size_t>(n.x()) * n.y() * n.z());
  auto index = [&](const Eigen::Vector3i& c) { return static_cast<size_t>(c.x() + n.x() * (c.y() + n.y() * c.z())); };
  for (Eigen::Index i = 0; i < x_m.cols(); ++i) bin[index(cell(x_m.col(i)))].push_back(static_cast<int>(i));
  auto v3 = [](const Vector3d& p) { return sdf::V3{p.x(), p.y(), p.z()}; };
  for (const auto& t : mesh.triangles) {
    const Vector3d& a = mesh.vertices_m[t[0]];
    const Vector3d& b = mesh.vertices_m[t[1]];
    const Vector3d& c = mesh.vertices_m[t[2]];
    const Eigen::Vector3i c0 = cell(a.cwiseMin(b).cwiseMin(c).array() - max_m);
    const Eigen::Vector3i c1 = cell(a.cwiseMax(b).cwiseMax(c).array() + max_m);
    for (int k = c0.z(); k <= c1.z(); ++k)
      for (int j = c0.y(); j <= c1.y(); ++j)
        for (int i = c0.x(); i <= c1.x(); ++i)
          for (int p : bin[index({i, j, k})]) {
            int region = 0;
            const sdf::V3 q = sdf::closest_on_triangle(v3(x_m.col(p)), v3(a), v3(b), v3(c), &region);
            const double d = (x_m.col(p) - Vector3d(q.x, q.y, q.z)).norm();
            depth[p] = std::min(depth[p], d);
          }
  }
  return depth;
}

}  // namespace

TissueModel build_tissue_model(const anatomy::TriangleMesh& surface_m, std::span<const Vector3d> fiducials_m,
                               const TissueModelSpec& spec) {
  if (!(spec.particle_radius_m > 0.0) || !(spec.voxel_m > 0.0) || !(spec.cluster_spacing_factor > 0.0))
    throw std::invalid_argument("build_tissue_model: particle radius " + mm(spec.particle_radius_m) + " mm, voxel " +
                                mm(spec.voxel_m) + " mm and cluster factor must be positive");
  if (surface_m.vertices_m.empty() || surface_m.triangles.empty())
    throw std::invalid_argument("build_tissue_model: the organ surface is empty");
  Vector3d lo = Vector3d::Constant(1e300), hi = Vector3d::Constant(-1e300);
  for (const Vector3d& v : surface_m.vertices_m) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Vector3d size = hi - lo;
  if (spec.particle_radius_m > size.minCoeff())
    throw std::invalid_argument("build_tissue_model: particle radius " + mm(spec.particle_radius_m) +
                                " mm is larger than the organ (" + mm(size.x()) + " x " + mm(size.y()) + " x " +
                                mm(size.z()) + " mm)");
  TissueModel model;
  model.spec = spec;
  model.interior_voxels_m = voxelise(surface_m, spec.voxel_m);
  if (model.interior_voxels_m.cols() == 0)
    throw std::invalid_argument("build_tissue_model: no voxel of " + mm(spec.voxel_m) +
                                " mm has its centre inside the organ");
  model.rest_m = greedy_sample(model.interior_voxels_m, spec.particle_radius_m);
  model.skin_depth_m = skin_depths(surface_m, model.rest_m, spec.particle_radius_m);
  // [soft-tissue "Cluster-based deformation"] overlapping cubical clusters
  model.clusters = pbd::grid_clusters(model.rest_m, spec.cluster_spacing_factor * spec.particle_radius_m,
                                      spec.cluster_overlap, spec.cluster_min_members);
  model.cluster_rest_centre_m.resize(3, static_cast<Eigen::Index>(model.clusters.size()));
  for (size_t c = 0; c < model.clusters.size(); ++c) {
    Vector3d s = Vector3d::Zero();
    for (int i : model.clusters[c]) s += model.rest_m.col(i);
    model.cluster_rest_centre_m.col(static_cast<Eigen::Index>(c)) = s / static_cast<double>(model.clusters[c].size());
  }
  model.surface_skin.reserve(surface_m.vertices_m.size());
  for (const Vector3d& v : surface_m.vertices_m) model.surface_skin.push_back(bind(v, model.cluster_rest_centre_m));
  model.fiducial_skin.reserve(fiducials_m.size());
  for (const Vector3d& f : fiducials_m) model.fiducial_skin.push_back(bind(f, model.cluster_rest_centre_m));
  build_tets(model, spec.tet_spacing_factor * spec.particle_radius_m);
  model.tet_skin.reserve(static_cast<size_t>(model.tet_vertices_m.cols()));
  for (Eigen::Index v = 0; v < model.tet_vertices_m.cols(); ++v)
    model.tet_skin.push_back(bind(model.tet_vertices_m.col(v), model.cluster_rest_centre_m));
  return model;
}

ClusterFrames::ClusterFrames(const TissueModel& model)
    : rotation(model.clusters.size(), Matrix3d::Identity()), centre_m(model.cluster_rest_centre_m) {}

// [soft-tissue "Cluster-based deformation"; heart paper eqs 7-8] shape matching per cluster:
// c = mean x_i, A = sum (x_i - c)(x0_i - c0)^T, R = U V^T from A's SVD (det fixed to +1)
void cluster_frames(const TissueModel& model, const Matrix3Xd& x_m, ClusterFrames* frames) {
  for (size_t c = 0; c < model.clusters.size(); ++c) {
    const auto& members = model.clusters[c];
    Vector3d centre = Vector3d::Zero();
    for (int i : members) centre += x_m.col(i);
    centre /= static_cast<double>(members.size());
    const Vector3d c0 = model.cluster_rest_centre_m.col(static_cast<Eigen::Index>(c));
    Matrix3d a = Matrix3d::Zero();
    for (int i : members) a += (x_m.col(i) - centre) * (model.rest_m.col(i) - c0).transpose();
    Eigen::JacobiSVD<Matrix3d> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Matrix3d u = svd.matrixU();
    if ((u * svd.matrixV().transpose()).determinant() < 0.0) u.col(2) = -u.col(2);
    frames->rotation[c] = u * svd.matrixV().transpose();
    frames->centre_m.col(static_cast<Eigen::Index>(c)) = centre;
  }
}

// [soft-tissue "Weighted matrix blending"] p = sum_k w_k (R_k p_local_k + c_k)
void skin_points(const ClusterFrames& frames, std::span<const SkinBinding> bindings, Matrix3Xd* out_m) {
  for (size_t n = 0; n < bindings.size(); ++n) {
    const SkinBinding& b = bindings[n];
    Vector3d p = Vector3d::Zero();
    for (int q = 0; q < b.count; ++q)
      p += b.weight[q] * (frames.rotation[b.cluster[q]] * b.local_m[q] + frames.centre_m.col(b.cluster[q]));
    out_m->col(static_cast<Eigen::Index>(n)) = p;
  }
}

}  // namespace pcisim::physics::soft_tissue
