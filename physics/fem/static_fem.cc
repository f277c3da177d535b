#include "physics/fem/static_fem.h"

#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#ifdef PCISIM_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#endif
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace pcisim::physics::fem {

// the sparse Cholesky factorisation of Newton's system: CHOLMOD's supernodal one where the build
// found it (libsuitesparse-dev; ~10x faster on the 3-D meshes here), Eigen's simplicial one
// elsewhere (the GPU machine). Both fail (info() != Success) on a matrix that is not positive
// definite, which is what the shift below looks for
namespace {
#ifdef PCISIM_HAVE_CHOLMOD
class Factorisation : public Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> {
 public:
  Factorisation() { cholmod().print = 0; }  // "not positive definite" is expected, not news
};
#else
using Factorisation = Eigen::SimplicialLLT<Eigen::SparseMatrix<double>>;
#endif
}  // namespace
namespace {

Eigen::Matrix3d shape_matrix(const Eigen::VectorXd& x, const std::array<int, 4>& t) {
  Eigen::Matrix3d d;
  for (int c = 0; c < 3; ++c) d.col(c) = x.segment<3>(3 * t[c + 1]) - x.segment<3>(3 * t[0]);
  return d;
}

// the energy's gradient over one tet's nodes from H = V P D_m^-T: nodes 1-3 take H's columns,
// node 0 minus their sum (F is linear in the nodes through D_s)
void scatter_columns(const Eigen::Matrix3d& h, const std::array<int, 4>& t, Eigen::VectorXd* g) {
  for (int c = 0; c < 3; ++c) g->segment<3>(3 * t[c + 1]) += h.col(c);
  g->segment<3>(3 * t[0]) -= h.col(0) + h.col(1) + h.col(2);
}

// the contacts' energy, and their gradient and Hessian where asked: per node, the deepest
// penetration of a support, and of a body through its face of least penetration
double contact_terms(const Eigen::VectorXd& x, const FemSolveOptions& o, Eigen::VectorXd* g,
                     std::vector<Eigen::Triplet<double>>* h) {
  double e = 0.0;
  const double k = o.penalty_n_per_m;
  auto add = [&](int v, double depth, const Eigen::Vector3d& n) {
    e += 0.5 * k * depth * depth;
    if (g) g->segment<3>(3 * v) -= k * depth * n;
    if (h)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) h->emplace_back(3 * v + r, 3 * v + c, k * n[r] * n[c]);
  };
  for (int v = 0; v < x.size() / 3; ++v) {
    const Eigen::Vector3d p = x.segment<3>(3 * v);
    for (const FemHalfSpace& s : o.supports) {
      const double depth = s.offset_m - s.normal.dot(p);
      if (depth > 0.0) add(v, depth, s.normal);
    }
    for (const FemConvexBody& b : o.bodies) {
      int face = -1;
      double least = -std::numeric_limits<double>::infinity();
      for (size_t f = 0; f < b.faces.size(); ++f) {
        const double s = b.faces[f].normal.dot(p) - b.faces[f].offset_m;  // < 0 inside that face
        if (s >= 0.0) {
          face = -1;
          break;
        }
        if (s > least) least = s, face = static_cast<int>(f);
      }
      if (face >= 0) add(v, -least, b.faces[face].normal);
    }
  }
  return e;
}

}  // namespace

Eigen::VectorXd StaticFem::lumped_masses_kg(double density_kg_per_m3) const {
  Eigen::VectorXd m = Eigen::VectorXd::Zero(node_count());
  for (size_t i = 0; i < mesh_.tets.size(); ++i)
    for (int v : mesh_.tets[i]) m[v] += 0.25 * density_kg_per_m3 * rest_volume_m3_[i];
  return m;
}

StaticFem::StaticFem(FemMesh mesh, const NeoHookean& material) : mesh_(std::move(mesh)), material_(material) {
  const int n = node_count();
  const Eigen::VectorXd x = rest_positions();
  for (size_t e = 0; e < mesh_.tets.size(); ++e) {
    const auto& t = mesh_.tets[e];
    for (int v : t)
      if (v < 0 || v >= n) throw std::invalid_argument("fem: tet " + std::to_string(e) + " names a node out of range");
    const Eigen::Matrix3d dm = shape_matrix(x, t);
    const double det = dm.determinant();
    const double scale = dm.colwise().norm().prod();
    if (!(std::abs(det) > 1e-12 * scale))
      throw std::invalid_argument("fem: tet " + std::to_string(e) + " is degenerate at rest");
    // a negatively oriented tet is reordered (swap two nodes): F must start at det +1
    if (det < 0.0) std::swap(mesh_.tets[e][2], mesh_.tets[e][3]);
    const Eigen::Matrix3d dm_ok = shape_matrix(x, mesh_.tets[e]);
    rest_inverse_.push_back(dm_ok.inverse());
    rest_volume_m3_.push_back(dm_ok.determinant() / 6.0);
  }
}

Eigen::VectorXd StaticFem::rest_positions() const {
  return Eigen::Map<const Eigen::VectorXd>(mesh_.rest_m.data(), 3 * mesh_.rest_m.cols());
}

double StaticFem::energy(const Eigen::VectorXd& x) const {
  double e = 0.0;
  for (size_t i = 0; i < mesh_.tets.size(); ++i)
    e += rest_volume_m3_[i] * energy_density(material_, shape_matrix(x, mesh_.tets[i]) * rest_inverse_[i]);
  return e;
}

void StaticFem::gradient(const Eigen::VectorXd& x, Eigen::VectorXd* g) const {
  g->setZero(x.size());
  for (size_t i = 0; i < mesh_.tets.size(); ++i) {
    const Eigen::Matrix3d f = shape_matrix(x, mesh_.tets[i]) * rest_inverse_[i];
    scatter_columns(rest_volume_m3_[i] * first_piola(material_, f) * rest_inverse_[i].transpose(), mesh_.tets[i], g);
  }
}

// each column of a tet's 12 x 12 block: the gradient's change for a unit move of one node along
// one axis (dD_s = e_k in that node's column; node 0 moves all three columns by -e_k)
void StaticFem::stiffness(const Eigen::VectorXd& x, Eigen::SparseMatrix<double>* k) const {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(mesh_.tets.size() * 144);
  for (size_t i = 0; i < mesh_.tets.size(); ++i) {
    const auto& t = mesh_.tets[i];
    const Eigen::Matrix3d f = shape_matrix(x, t) * rest_inverse_[i];
    for (int a = 0; a < 4; ++a) {
      for (int dim = 0; dim < 3; ++dim) {
        Eigen::Matrix3d dds = Eigen::Matrix3d::Zero();
        if (a == 0) {
          dds.row(dim).setConstant(-1.0);
        } else {
          dds(dim, a - 1) = 1.0;
        }
        const Eigen::Matrix3d dh = rest_volume_m3_[i] * first_piola_differential(material_, f, dds * rest_inverse_[i]) *
                                   rest_inverse_[i].transpose();
        const int col = 3 * t[a] + dim;
        const Eigen::Vector3d d0 = -(dh.col(0) + dh.col(1) + dh.col(2));
        for (int r = 0; r < 3; ++r) {
          triplets.emplace_back(3 * t[0] + r, col, d0[r]);
          for (int c = 0; c < 3; ++c) triplets.emplace_back(3 * t[c + 1] + r, col, dh(r, c));
        }
      }
    }
  }
  const int n = 3 * node_count();
  k->resize(n, n);
  k->setFromTriplets(triplets.begin(), triplets.end());
}

FemSolveReport StaticFem::solve(const FemBoundary& bc, Eigen::VectorXd* x, const FemSolveOptions& options) const {
  const int n = 3 * node_count();
  if (static_cast<int>(bc.fixed.size()) != n || bc.target_m.size() != n)
    throw std::invalid_argument("fem: the boundary needs one entry per degree of freedom (3 per node)");
  if (options.external_force_n.size() != 0 && options.external_force_n.size() != n)
    throw std::invalid_argument("fem: the external force needs one entry per degree of freedom");
  if (x->size() != n) *x = rest_positions();
  const Eigen::VectorXd f_ext = options.external_force_n.size() ? options.external_force_n : Eigen::VectorXd::Zero(n);
  // the free DOFs, compacted
  std::vector<int> free_index(n, -1);
  int free_count = 0;
  for (int i = 0; i < n; ++i)
    if (!bc.fixed[i]) free_index[i] = free_count++;
  auto total_energy = [&](const Eigen::VectorXd& y) {
    return energy(y) - f_ext.dot(y) + contact_terms(y, options, nullptr, nullptr);
  };

  const Eigen::VectorXd start = *x;
  FemSolveReport report;
  Eigen::VectorXd g, g_free(free_count), step(free_count);
  Eigen::SparseMatrix<double> k;
  Factorisation llt;
  bool analysed = false;
  double last_shift = 0.0;
  Eigen::SparseMatrix<double> identity(free_count, free_count);
  identity.setIdentity();
  const int steps = std::max(1, options.load_steps);
  for (int s = 1; s <= steps; ++s) {
    const double a = static_cast<double>(s) / steps;
    for (int i = 0; i < n; ++i)
      if (bc.fixed[i]) (*x)[i] = start[i] + a * (bc.target_m[i] - start[i]);
    report.converged = false;
    for (int it = 0; it < options.max_newton_iterations; ++it) {
      gradient(*x, &g);
      g -= f_ext;
      contact_terms(*x, options, &g, nullptr);
      for (int i = 0; i < n; ++i)
        if (free_index[i] >= 0) g_free[free_index[i]] = g[i];
      report.residual_n = free_count ? g_free.cwiseAbs().maxCoeff() : 0.0;
      if (!std::isfinite(report.residual_n)) return report;  // an inverted start: not converged
      if (report.residual_n <= options.force_tolerance_n) {
        report.converged = true;
        break;
      }
      ++report.newton_iterations;
      // the stiffness over the free DOFs
      stiffness(*x, &k);
      std::vector<Eigen::Triplet<double>> contact_h;
      contact_terms(*x, options, nullptr, &contact_h);
      if (!contact_h.empty()) {
        Eigen::SparseMatrix<double> kc(n, n);
        kc.setFromTriplets(contact_h.begin(), contact_h.end());
        k += kc;
      }
      std::vector<Eigen::Triplet<double>> kept;
      kept.reserve(k.nonZeros());
      for (int c = 0; c < k.outerSize(); ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator e(k, c); e; ++e)
          if (free_index[e.row()] >= 0 && free_index[e.col()] >= 0)
            kept.emplace_back(free_index[e.row()], free_index[e.col()], e.value());
      Eigen::SparseMatrix<double> kf(free_count, free_count);
      kf.setFromTriplets(kept.begin(), kept.end());
      // Newton's step; where K is not positive definite, shifted toward the identity until it is.
      // The pattern is the same every iteration (ordered once); the last shift that worked is
      // where the next iteration starts (a tenth of it), so an indefinite K costs few factorisations
      const double diag = std::max(kf.diagonal().cwiseAbs().maxCoeff(), 1e-12);
      if (!analysed) {
        llt.analyzePattern(kf);
        analysed = true;
      }
      double shift = last_shift > 0.0 ? 0.1 * last_shift : 0.0;
      if (shift > 0.0 && shift < 1e-6 * diag) shift = 0.0;
      for (int attempt = 0; attempt < 30; ++attempt) {
        Eigen::SparseMatrix<double> m = kf;
        if (shift > 0.0) m += shift * identity;
        llt.factorize(m);
        if (llt.info() == Eigen::Success) {
          step = llt.solve(-g_free);
          if (step.dot(g_free) < 0.0) break;
        }
        shift = shift > 0.0 ? 10.0 * shift : 1e-6 * diag;
      }
      last_shift = shift;
      // backtracking on the energy (Armijo); an inverted tet has infinite energy
      const double e0 = total_energy(*x), slope = step.dot(g_free);
      double alpha = 1.0;
      Eigen::VectorXd trial = *x;
      bool accepted = false;
      for (int ls = 0; ls < 40; ++ls) {
        trial = *x;
        for (int i = 0; i < n; ++i)
          if (free_index[i] >= 0) trial[i] += alpha * step[free_index[i]];
        if (total_energy(trial) <= e0 + 1e-4 * alpha * slope) {
          accepted = true;
          break;
        }
        alpha *= 0.5;
      }
      if (!accepted) break;  // no decrease along Newton's direction: as converged as it gets
      *x = trial;
    }
  }
  return report;
}

}  // namespace pcisim::physics::fem
