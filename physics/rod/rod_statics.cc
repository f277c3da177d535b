#include "physics/rod/rod_statics.h"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "physics/rod/cosserat_constraints.h"

namespace pcisim::physics::rod {
namespace {

// one energy term and the global unknowns it depends on, in the order of its local delta:
// stretch-shear j: [rotation j, node j (if free), node j + 1]; bend-twist pair j: [rotation
// j - 1 (if not the clamp), rotation j]
struct Term {
  bool stretch = true;
  int index = 0;
  int ndof = 0;
  std::array<int, 9> dof{};
};

int rotation_dof(int segment) {
  return 6 * segment;
}
int node_dof(int node) {
  return 6 * (node - 1) + 3;
}  // node >= 1

Eigen::Quaterniond rotated(const Eigen::Quaterniond& q, const double* phi) {
  const Eigen::Vector3d v(phi[0], phi[1], phi[2]);
  const double angle = v.norm();
  if (angle < 1e-300) return q;
  return (q * Eigen::Quaterniond(Eigen::AngleAxisd(angle, v / angle))).normalized();
}

std::vector<Term> make_terms(const CosseratRod& rod) {
  std::vector<Term> terms;
  const int n = rod.segment_count();
  for (int j = 0; j < n; ++j) {
    Term t;
    t.stretch = true;
    t.index = j;
    for (int k = 0; k < 3; ++k) t.dof[t.ndof++] = rotation_dof(j) + k;
    if (j > 0)
      for (int k = 0; k < 3; ++k) t.dof[t.ndof++] = node_dof(j) + k;
    for (int k = 0; k < 3; ++k) t.dof[t.ndof++] = node_dof(j + 1) + k;
    terms.push_back(t);
  }
  for (int j = 0; j < n; ++j) {
    Term t;
    t.stretch = false;
    t.index = j;
    if (j > 0)
      for (int k = 0; k < 3; ++k) t.dof[t.ndof++] = rotation_dof(j - 1) + k;
    for (int k = 0; k < 3; ++k) t.dof[t.ndof++] = rotation_dof(j) + k;
    terms.push_back(t);
  }
  return terms;
}

// the term's elastic energy with its unknowns moved by delta (local order, see Term)
double term_energy(const CosseratRod& rod, const Term& t, const double* delta) {
  const auto x = rod.nodes_m();
  const auto q = rod.orientations();
  if (t.stretch) {
    const int j = t.index;
    const Eigen::Quaterniond qj = rotated(q[j], delta);
    int o = 3;
    Eigen::Vector3d p1 = x[j];
    if (j > 0) {
      p1 += Eigen::Vector3d(delta[o], delta[o + 1], delta[o + 2]);
      o += 3;
    }
    const Eigen::Vector3d p2 = x[j + 1] + Eigen::Vector3d(delta[o], delta[o + 1], delta[o + 2]);
    const double l = rod.segment_length_m();
    const Eigen::Vector3d gamma = stretch_shear_strain(p1, p2, qj, l);
    return 0.5 * l * gamma.cwiseProduct(gamma).dot(rod.stretch_shear_stiffness(j));
  }
  const int j = t.index;
  Eigen::Quaterniond q1 = rod.pair_first_frame(j);
  int o = 0;
  if (j > 0) {
    q1 = rotated(q1, delta);
    o = 3;
  }
  const Eigen::Quaterniond q2 = rotated(q[j], delta + o);
  const double lb = rod.dual_length_m(j);
  const Eigen::Vector3d omega = bend_twist_strain(q1, q2, lb, rod.rest_darboux_per_m(j));
  return 0.5 * lb * omega.cwiseProduct(omega).dot(rod.bend_twist_stiffness(j));
}

Eigen::Vector3d node_load_n(const CosseratRod& rod, int node, double scale) {
  return scale * (rod.node_force_n(node) + rod.node_own_mass_kg(node) * rod.params().gravity_m_per_s2);
}

// Newton update, geometrically exact in the rotations: each segment's strain in its material
// frame is moved by the linearised change, Gamma_m + R^T (dx2 - dx1) / l - phi x (Gamma_m + e3),
// and the nodes are rebuilt from the clamp, x_{j+1} = x_j + l R(q_j exp(phi_j)) (e3 + Gamma_m).
// Moving the nodes linearly instead would stretch the segments by l phi^2 / 2 wherever they
// turn, which the stiff axial term punishes: Newton's steps then shrink to nothing.
void apply_update(CosseratRod& rod, const Eigen::VectorXd& d, std::vector<Eigen::Vector3d>& strain) {
  auto x = rod.mutable_nodes_m();
  auto q = rod.mutable_orientations();
  const double l = rod.segment_length_m();
  for (int j = 0; j < rod.segment_count(); ++j) {
    const Eigen::Vector3d gm = stretch_shear_strain(x[j], x[j + 1], q[j], l);
    const Eigen::Vector3d d1 = j > 0 ? Eigen::Vector3d(d.segment<3>(node_dof(j))) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d d2 = d.segment<3>(node_dof(j + 1));
    const Eigen::Vector3d phi = d.segment<3>(rotation_dof(j));
    strain[j] = gm + q[j].conjugate() * (d2 - d1) / l - phi.cross(gm + Eigen::Vector3d::UnitZ());
  }
  for (int j = 0; j < rod.segment_count(); ++j) {
    q[j] = rotated(q[j], d.data() + rotation_dof(j));
    x[j + 1] = x[j] + l * (q[j] * (Eigen::Vector3d::UnitZ() + strain[j]));
  }
}

}  // namespace

double rod_energy_j(const CosseratRod& rod, double load_scale) {
  static const std::array<double, 9> zero{};
  double e = 0.0;
  for (const Term& t : make_terms(rod)) e += term_energy(rod, t, zero.data());
  const auto x = rod.nodes_m();
  for (int i = 1; i < rod.node_count(); ++i) e -= node_load_n(rod, i, load_scale).dot(x[i]);
  return e;
}

StaticSolveResult solve_static(CosseratRod& rod, const StaticSolveOptions& options) {
  const int n = rod.segment_count();
  const int dofs = 6 * n;
  const double length = rod.params().length_m;
  const std::vector<Term> terms = make_terms(rod);
  // central-difference steps: rotations in rad, positions scaled by the rod's length
  auto fd_step = [&](int dof, double rel) { return (dof % 6) < 3 ? rel : rel * length; };

  StaticSolveResult result;
  Eigen::VectorXd grad(dofs), delta(dofs);
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::SparseMatrix<double> hessian(dofs, dofs);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  std::vector<Eigen::Vector3d> saved_x(rod.node_count());
  std::vector<Eigen::Quaterniond> saved_q(n);
  std::vector<Eigen::Vector3d> strain(n);
  bool all_converged = true;

  for (int s = 1; s <= options.load_steps; ++s) {
    const double scale = static_cast<double>(s) / options.load_steps;
    bool converged = false;
    for (int it = 0; it < options.max_newton_iterations && !converged; ++it) {
      ++result.newton_iterations;
      grad.setZero();
      triplets.clear();
      for (const Term& t : terms) {
        std::array<double, 9> d{};
        for (int a = 0; a < t.ndof; ++a) {
          const double ha = fd_step(t.dof[a], 1e-6);
          d[a] = ha;
          const double ep = term_energy(rod, t, d.data());
          d[a] = -ha;
          const double em = term_energy(rod, t, d.data());
          d[a] = 0.0;
          grad[t.dof[a]] += (ep - em) / (2.0 * ha);
        }
        for (int a = 0; a < t.ndof; ++a) {
          const double ha = fd_step(t.dof[a], 1e-5);
          for (int b = a; b < t.ndof; ++b) {
            const double hb = fd_step(t.dof[b], 1e-5);
            double e4[4];
            const double sa[4] = {1, 1, -1, -1}, sb[4] = {1, -1, 1, -1};
            for (int c = 0; c < 4; ++c) {
              d[a] += sa[c] * ha;
              d[b] += sb[c] * hb;
              e4[c] = term_energy(rod, t, d.data());
              d[a] = 0.0;
              d[b] = 0.0;
            }
            const double hab = (e4[0] - e4[1] - e4[2] + e4[3]) / (4.0 * ha * hb);
            triplets.emplace_back(t.dof[a], t.dof[b], hab);
            if (a != b) triplets.emplace_back(t.dof[b], t.dof[a], hab);
          }
        }
      }
      for (int i = 1; i <= n; ++i) grad.segment<3>(node_dof(i)) -= node_load_n(rod, i, scale);
      hessian.setFromTriplets(triplets.begin(), triplets.end());

      // a positive definite system: shift the diagonal until LDL^T has positive pivots
      double shift = 0.0;
      const double diag_scale = hessian.diagonal().cwiseAbs().maxCoeff();
      for (int tries = 0; tries < 30; ++tries) {
        Eigen::SparseMatrix<double> shifted = hessian;
        if (shift > 0.0)
          for (int k = 0; k < dofs; ++k) shifted.coeffRef(k, k) += shift;
        ldlt.compute(shifted);
        if (ldlt.info() == Eigen::Success && ldlt.vectorD().minCoeff() > 0.0) break;
        shift = shift == 0.0 ? 1e-10 * diag_scale : 10.0 * shift;
      }
      delta = -ldlt.solve(grad);
      if (!delta.allFinite()) break;

      // converged: the update is below the tolerance (U's changes are at round-off level there)
      if (delta.cwiseAbs().maxCoeff() < options.step_tolerance * length) {
        apply_update(rod, delta, strain);
        converged = true;
        break;
      }
      // backtracking on U (accepting changes at round-off level)
      const double e0 = rod_energy_j(rod, scale);
      std::copy(rod.nodes_m().begin(), rod.nodes_m().end(), saved_x.begin());
      std::copy(rod.orientations().begin(), rod.orientations().end(), saved_q.begin());
      double step = 1.0;
      for (int ls = 0; ls < 40; ++ls) {
        apply_update(rod, step * delta, strain);
        const double e1 = rod_energy_j(rod, scale);
        if (e1 <= e0 + 1e-12 * std::abs(e0) + 1e-300) break;
        std::copy(saved_x.begin(), saved_x.end(), rod.mutable_nodes_m().begin());
        std::copy(saved_q.begin(), saved_q.end(), rod.mutable_orientations().begin());
        step *= 0.5;
        if (ls == 39) step = 0.0;
      }
      if (step == 0.0) break;  // no descent along Newton's direction: give up on this load step
    }
    all_converged = all_converged && converged;
  }
  result.converged = all_converged;
  result.energy_j = rod_energy_j(rod, 1.0);
  return result;
}

}  // namespace pcisim::physics::rod
