#include "modeling/heart/heart_elastic_fit.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <utility>

#include "anatomy/heart/template_heart_surface.h"
#include "realtime/percentile.h"

namespace pcisim::modeling {
namespace {

using Eigen::Matrix3Xd;
using Eigen::Vector3d;
using SparseMatrix = Eigen::SparseMatrix<double>;
using Triplet = Eigen::Triplet<double>;

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / double(v.size());
}

// the epicardium of a mesh: its vertices (global indices), their rings, its triangles
struct Epicardium {
  std::vector<int> vertex;                   // local -> mesh vertex
  std::vector<int> local;                    // mesh vertex -> local (-1 off the epicardium)
  std::vector<std::array<int, 3>> faces;     // local indices, counter-clockwise from outside
  std::vector<std::vector<int>> neighbours;  // one ring, local
};

Epicardium epicardium_of(const anatomy::HeartMesh& mesh) {
  Epicardium e;
  e.local.assign(mesh.vertices_m.cols(), -1);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.face_markers[f] != anatomy::kEpicardium) continue;
    std::array<int, 3> t;
    for (int c = 0; c < 3; ++c) {
      const int v = mesh.faces[f][c];
      if (e.local[v] < 0) {
        e.local[v] = static_cast<int>(e.vertex.size());
        e.vertex.push_back(v);
      }
      t[c] = e.local[v];
    }
    e.faces.push_back(t);
  }
  std::vector<std::set<int>> ring(e.vertex.size());
  for (const auto& t : e.faces)
    for (int c = 0; c < 3; ++c) {
      ring[t[c]].insert(t[(c + 1) % 3]);
      ring[t[c]].insert(t[(c + 2) % 3]);
    }
  for (const auto& r : ring) e.neighbours.emplace_back(r.begin(), r.end());
  return e;
}

// area-weighted vertex normals of the epicardium at positions x (mesh vertices, columns)
std::vector<Vector3d> vertex_normals(const Epicardium& e, const Matrix3Xd& x) {
  std::vector<Vector3d> n(e.vertex.size(), Vector3d::Zero());
  for (const auto& t : e.faces) {
    const Vector3d a = x.col(e.vertex[t[0]]), b = x.col(e.vertex[t[1]]), c = x.col(e.vertex[t[2]]);
    const Vector3d area2 = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) n[t[k]] += area2;
  }
  for (auto& v : n) v.normalize();
  return n;
}

// volume enclosed by the epicardium (divergence theorem), x in mm -> ml
double enclosed_ml(const Epicardium& e, const Matrix3Xd& x_mm) {
  double v6 = 0;
  for (const auto& t : e.faces)
    v6 += x_mm.col(e.vertex[t[0]]).dot(x_mm.col(e.vertex[t[1]]).cross(x_mm.col(e.vertex[t[2]])));
  return v6 / 6.0 / 1000.0;
}

double tet_volume6(const Matrix3Xd& x, const std::array<int, 4>& t) {
  const Vector3d a = x.col(t[0]);
  return (x.col(t[1]) - a).cross(x.col(t[2]) - a).dot(x.col(t[3]) - a);
}

// smallest ratio of a tet's volume at x to its volume at x0 (negative: inverted)
double min_volume_ratio(const anatomy::HeartMesh& mesh, const Matrix3Xd& x0, const Matrix3Xd& x) {
  double worst = std::numeric_limits<double>::infinity();
  for (const auto& t : mesh.tets) worst = std::min(worst, tet_volume6(x, t) / tet_volume6(x0, t));
  return worst;
}

// the targets of one round: signed distance along each epicardial normal to the outline (NaN:
// none found, or an outlier against its neighbours')
struct Targets {
  std::vector<double> t_mm;
  int found = 0, outliers = 0;
};

Targets find_targets(const FloatImage& field, const Epicardium& e, const Matrix3Xd& x_mm,
                     const std::vector<Vector3d>& normal, const HeartElasticFitOptions& o) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> raw(e.vertex.size(), nan);
  for (size_t i = 0; i < e.vertex.size(); ++i)
    raw[i] = outline_along_normal_mm(field, x_mm.col(e.vertex[i]), normal[i], o);
  // outliers: against the median over the two rings around each vertex
  Targets r;
  r.t_mm = raw;
  std::vector<double> near;
  for (size_t i = 0; i < e.vertex.size(); ++i) {
    if (std::isnan(raw[i])) continue;
    std::set<int> two_rings;
    for (int a : e.neighbours[i]) {
      two_rings.insert(a);
      for (int b : e.neighbours[a]) two_rings.insert(b);
    }
    two_rings.erase(static_cast<int>(i));
    near.clear();
    for (int a : two_rings)
      if (!std::isnan(raw[a])) near.push_back(raw[a]);
    if (near.size() >= 3 && std::abs(raw[i] - realtime::percentile(near, 0.5)) > o.outlier_mm) {
      r.t_mm[i] = nan;
      ++r.outliers;
      continue;
    }
    ++r.found;
  }
  return r;
}

// step 3: the epicardium's displacement, the targets smoothed over the surface
Matrix3Xd smooth_displacement(const Epicardium& e, const Targets& targets, const std::vector<Vector3d>& normal,
                              double smoothing) {
  const int n = static_cast<int>(e.vertex.size());
  std::vector<Triplet> a;
  Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(n, 3);
  for (int i = 0; i < n; ++i) {
    const double w = std::isnan(targets.t_mm[i]) ? 0.0 : 1.0;
    a.emplace_back(i, i, w + smoothing * double(e.neighbours[i].size()));
    for (int j : e.neighbours[i]) a.emplace_back(i, j, -smoothing);
    if (w > 0) rhs.row(i) = (targets.t_mm[i] * normal[i]).transpose();
  }
  SparseMatrix m(n, n);
  m.setFromTriplets(a.begin(), a.end());
  Eigen::SimplicialLDLT<SparseMatrix> solver(m);
  if (solver.info() != Eigen::Success) throw std::runtime_error("heart fit: the surface system is singular");
  const Eigen::MatrixX3d d = solver.solve(rhs);
  return d.transpose();
}

// step 4: every vertex off the epicardium at the mean of its tet-edge neighbours (the graph
// Laplacian zero there), the epicardium's displacement given
class HarmonicExtension {
 public:
  HarmonicExtension(const anatomy::HeartMesh& mesh, const Epicardium& e) : local_(e.local) {
    const int n = static_cast<int>(mesh.vertices_m.cols());
    std::set<std::pair<int, int>> edges;
    for (const auto& t : mesh.tets)
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b) edges.insert(std::minmax(t[a], t[b]));
    free_.assign(n, -1);
    for (int v = 0; v < n; ++v)
      if (e.local[v] < 0) free_[v] = free_count_++;
    std::vector<Triplet> a;
    std::vector<double> degree(free_count_, 0.0);
    for (const auto& [u, v] : edges) {
      for (const auto& [p, q] : {std::pair{u, v}, std::pair{v, u}}) {
        if (free_[p] < 0) continue;
        degree[free_[p]] += 1;
        if (free_[q] >= 0) {
          a.emplace_back(free_[p], free_[q], -1.0);
        } else {
          boundary_edges_.push_back({free_[p], e.local[q]});
        }
      }
    }
    for (int i = 0; i < free_count_; ++i) a.emplace_back(i, i, degree[i]);
    SparseMatrix m(free_count_, free_count_);
    m.setFromTriplets(a.begin(), a.end());
    solver_.compute(m);
    if (solver_.info() != Eigen::Success) throw std::runtime_error("heart fit: the interior system is singular");
  }

  // the displacement of every mesh vertex from the epicardium's (local order)
  Matrix3Xd extend(const Matrix3Xd& surface) const {
    Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(free_count_, 3);
    for (const auto& [f, s] : boundary_edges_) rhs.row(f) += surface.col(s).transpose();
    const Eigen::MatrixX3d inner = solver_.solve(rhs);
    Matrix3Xd d(3, local_.size());
    for (size_t v = 0; v < local_.size(); ++v)
      d.col(v) = local_[v] >= 0 ? Vector3d(surface.col(local_[v])) : Vector3d(inner.row(free_[v]).transpose());
    return d;
  }

 private:
  std::vector<int> local_, free_;
  int free_count_ = 0;
  std::vector<std::pair<int, int>> boundary_edges_;  // (free row, epicardial local)
  Eigen::SimplicialLDLT<SparseMatrix> solver_;
};

}  // namespace

FloatImage heart_outline_field(const anatomy::Volume& ct, const Vector3d& lo_mm, const Vector3d& hi_mm,
                               const anatomy::VesselTree& tree, const HeartElasticFitOptions& o) {
  const ImageGrid fine = ImageGrid::of(ct);
  // the box in index space (any direction matrix: all eight corners), clamped to the CT
  Vector3d lo_i = Vector3d::Constant(std::numeric_limits<double>::infinity()), hi_i = -lo_i;
  for (int c = 0; c < 8; ++c) {
    const Vector3d p((c & 1) ? hi_mm.x() : lo_mm.x(), (c & 2) ? hi_mm.y() : lo_mm.y(), (c & 4) ? hi_mm.z() : lo_mm.z());
    const Vector3d q = fine.continuous_index(p);
    lo_i = lo_i.cwiseMin(q);
    hi_i = hi_i.cwiseMax(q);
  }
  std::array<int64_t, 3> f{}, lo{}, dims{};
  for (int a = 0; a < 3; ++a) {
    f[a] = std::max<int64_t>(1, std::llround(o.block_mm / ct.spacing_mm[a]));
    lo[a] = std::clamp<int64_t>(static_cast<int64_t>(std::floor(lo_i[a])), 0, ct.dims[a]);
    const int64_t hi = std::clamp<int64_t>(static_cast<int64_t>(std::ceil(hi_i[a])) + 1, 0, ct.dims[a]);
    dims[a] = (hi - lo[a]) / f[a];
    if (dims[a] < 2)
      throw std::invalid_argument(
          fmt::format("heart fit: the placed heart lies outside the CT (index axis {}: {:.0f}..{:.0f} of 0..{})", a,
                      lo_i[a], hi_i[a], ct.dims[a] - 1));
  }
  FloatImage field;
  field.grid = fine;
  field.grid.dims = dims;
  field.grid.spacing_mm = ct.spacing_mm.cwiseProduct(Vector3d(double(f[0]), double(f[1]), double(f[2])));
  // a block's mean sits at its voxels' centre
  field.grid.origin_mm =
      fine.physical_mm(Vector3d(lo[0] + 0.5 * (f[0] - 1), lo[1] + 0.5 * (f[1] - 1), lo[2] + 0.5 * (f[2] - 1)));
  field.v.assign(field.grid.size(), 0.0f);
  const double per_block = 1.0 / double(f[0] * f[1] * f[2]);
  for (int64_t k = 0; k < dims[2]; ++k)
    for (int64_t j = 0; j < dims[1]; ++j)
      for (int64_t i = 0; i < dims[0]; ++i) {
        double sum = 0;
        for (int64_t c = 0; c < f[2]; ++c)
          for (int64_t b = 0; b < f[1]; ++b)
            for (int64_t a = 0; a < f[0]; ++a)
              sum += ct.hu(lo[0] + i * f[0] + a, lo[1] + j * f[1] + b, lo[2] + k * f[2] + c);
        field.v[field.grid.index(i, j, k)] = static_cast<float>(sum * per_block);
      }
  // the coronaries run on the heart in fat: their lumens are not the heart's outline
  const float painted = static_cast<float>(o.tissue_hu - 100.0);
  const ImageGrid& g = field.grid;
  for (const auto& branch : tree.branches) {
    if (branch.name == "aorta") continue;
    for (const auto& p : branch.points) {
      const Vector3d p_mm = 1e3 * p.position_m;
      const double r_mm = 1e3 * p.radius_m + o.vessel_clearance_mm;
      const Vector3d c = g.continuous_index(p_mm);
      std::array<int64_t, 3> a{}, b{};
      for (int d = 0; d < 3; ++d) {
        const double reach = r_mm / g.spacing_mm[d] + 1;
        a[d] = std::max<int64_t>(0, static_cast<int64_t>(std::floor(c[d] - reach)));
        b[d] = std::min<int64_t>(g.dims[d] - 1, static_cast<int64_t>(std::ceil(c[d] + reach)));
      }
      for (int64_t k = a[2]; k <= b[2]; ++k)
        for (int64_t j = a[1]; j <= b[1]; ++j)
          for (int64_t i = a[0]; i <= b[0]; ++i)
            if ((g.physical_mm(Vector3d(double(i), double(j), double(k))) - p_mm).norm() <= r_mm)
              field.v[g.index(i, j, k)] = painted;
    }
  }
  return field;
}

double outline_along_normal_mm(const FloatImage& field, const Vector3d& p_mm, const Vector3d& normal,
                               const HeartElasticFitOptions& o) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const int steps = static_cast<int>(std::ceil(o.search_mm / o.step_mm));
  const int run = std::max(1, static_cast<int>(std::lround(o.run_mm / o.step_mm)));
  // the field minus the threshold at t = (s - steps) * step, s = 0 .. 2 steps, and run more each way
  thread_local std::vector<double> v;
  v.resize(2 * (steps + run) + 1);
  for (size_t s = 0; s < v.size(); ++s) {
    const double t = (static_cast<double>(s) - steps - run) * o.step_mm;
    v[s] =
        field.at(field.grid.continuous_index(p_mm + t * normal), std::numeric_limits<float>::quiet_NaN()) - o.tissue_hu;
  }
  // heart (above) for run_mm behind, outside (at or below) for run_mm ahead: a noise dip in the
  // heart or a speck in the fat is no outline
  double best = nan;
  for (int s = run; s + 1 + run < static_cast<int>(v.size()); ++s) {
    if (!(v[s] > 0 && v[s + 1] <= 0)) continue;
    bool clean = true;
    for (int k = 1; k <= run && clean; ++k) clean = v[s - k] > 0 && v[s + 1 + k] <= 0;
    if (!clean) continue;
    const double crossing = (s - steps - run) * o.step_mm + o.step_mm * v[s] / (v[s] - v[s + 1]);
    if (std::abs(crossing) > o.search_mm) continue;
    if (std::isnan(best) || std::abs(crossing) < std::abs(best)) best = crossing;
  }
  return best;
}

HeartElasticFit fit_heart_elastic(const anatomy::Volume& ct, const anatomy::VesselTree& tree,
                                  const anatomy::HeartPose& pose, const anatomy::HeartMesh& template_mesh,
                                  const HeartElasticFitOptions& o) {
  HeartElasticFit fit;
  const Epicardium e = epicardium_of(template_mesh);
  fit.epicardial_vertices = static_cast<int>(e.vertex.size());
  if (e.vertex.empty()) throw std::invalid_argument("heart fit: the template mesh has no epicardium");

  // the placed mesh, case frame, mm
  const int n = static_cast<int>(template_mesh.vertices_m.cols());
  Matrix3Xd x0(3, n);
  for (int v = 0; v < n; ++v) x0.col(v) = 1e3 * pose.to_case(template_mesh.vertices_m.col(v));
  const Vector3d lo = x0.rowwise().minCoeff().array() - o.search_mm - 2 * o.block_mm;
  const Vector3d hi = x0.rowwise().maxCoeff().array() + o.search_mm + 2 * o.block_mm;
  const FloatImage field = heart_outline_field(ct, lo, hi, tree, o);
  const HarmonicExtension extension(template_mesh, e);

  auto outline_stats = [&](const Targets& t, double* mean_mm, double* p95_mm) {
    std::vector<double> d;
    for (double x : t.t_mm)
      if (!std::isnan(x)) d.push_back(std::abs(x));
    *mean_mm = mean(d);
    *p95_mm = realtime::percentile(d, 0.95);
  };

  Matrix3Xd x = x0;
  for (int round = 0; round < o.rounds; ++round) {
    const std::vector<Vector3d> normal = vertex_normals(e, x);
    const Targets targets = find_targets(field, e, x, normal, o);
    if (round == 0) outline_stats(targets, &fit.outline_before_mean_mm, &fit.outline_before_p95_mm);
    fit.targets = targets.found;
    fit.outliers = targets.outliers;
    if (targets.found < fit.epicardial_vertices / 4) {
      fit.notes.push_back(fmt::format(
          "the heart's outline was found from {} of {} epicardial vertices in round {} (under a quarter): the "
          "template is left as placed from there",
          targets.found, fit.epicardial_vertices, round + 1));
      break;
    }
    x += extension.extend(smooth_displacement(e, targets, normal, o.smoothing));
    ++fit.rounds_run;
  }

  // step 5: no tetrahedron inverted or crushed
  Matrix3Xd total = x - x0;
  fit.min_tet_volume_ratio = min_volume_ratio(template_mesh, x0, x);
  while (fit.min_tet_volume_ratio < o.min_tet_volume_fraction && fit.backoff > 0.01) {
    fit.backoff *= 0.8;
    x = x0 + fit.backoff * total;
    fit.min_tet_volume_ratio = min_volume_ratio(template_mesh, x0, x);
  }
  if (fit.min_tet_volume_ratio < o.min_tet_volume_fraction) {
    // the bound is not met even scaled back to 1 %: the template as placed
    x = x0;
    fit.backoff = 0;
    fit.rounds_run = 0;
    fit.min_tet_volume_ratio = 1;
    fit.notes.push_back("the fit would crush a tetrahedron at any scale: the template is left as placed");
  } else if (fit.backoff < 1)
    fit.notes.push_back(
        fmt::format("the fit was scaled back to {:.0f} % to keep every tetrahedron above {:.0f} % of "
                    "its volume",
                    100 * fit.backoff, 100 * o.min_tet_volume_fraction));

  const Targets after = find_targets(field, e, x, vertex_normals(e, x), o);
  outline_stats(after, &fit.outline_after_mean_mm, &fit.outline_after_p95_mm);
  const Eigen::VectorXd move = (x - x0).colwise().norm();
  fit.move_mean_mm = move.mean();
  fit.move_max_mm = move.maxCoeff();
  fit.volume_placed_ml = enclosed_ml(e, x0);
  fit.volume_fitted_ml = enclosed_ml(e, x);
  fit.vertices_m.resize(3, n);
  for (int v = 0; v < n; ++v) fit.vertices_m.col(v) = pose.to_template(1e-3 * x.col(v));
  return fit;
}

}  // namespace pcisim::modeling
