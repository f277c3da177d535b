#pragma once
// A static hyperelastic finite-element solve on linear tetrahedra (issue #16 item 5): the
// independent reference the soft tissue's PBD is calibrated against. Minimises
//   E(x) = sum_e V_e psi(F_e) - f_ext . x,   F_e = D_s(x) D_m^-1
// over the free degrees of freedom by Newton's method (sparse Cholesky, shifted toward the identity
// when the stiffness is not positive definite, backtracking line search on E), with the
// prescribed ones stepped from rest to their targets over a few load steps. Not real time: a
// benchmark and test tool.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <cstdint>
#include <vector>

#include "physics/fem/neo_hookean.h"

namespace pcisim::physics::fem {

struct FemMesh {
  Eigen::Matrix3Xd rest_m;               // node positions at rest
  std::vector<std::array<int, 4>> tets;  // node indices, any orientation
};

// per degree of freedom (3 per node, x y z): prescribed or free
struct FemBoundary {
  std::vector<uint8_t> fixed;  // 3n entries; 1 = prescribed
  Eigen::VectorXd target_m;    // 3n; where a prescribed DOF ends (read where fixed)
};

// frictionless penalty contact, energy k/2 d^2 for a node d deep: a half-space whose free side
// is n . x >= offset (the support), or a convex body, inside where every n_i . x <= d_i (the
// probe), a node inside pushed out through its face of least penetration
struct FemHalfSpace {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  // unit
  double offset_m = 0.0;
};
struct FemConvexBody {
  std::vector<FemHalfSpace> faces;  // inside: normal . x <= offset for all
};

struct FemSolveOptions {
  int load_steps = 4;                  // the prescribed DOFs move from rest to target in this many steps
  int max_newton_iterations = 60;      // per load step
  double force_tolerance_n = 1e-9;     // largest free residual force at convergence
  Eigen::VectorXd external_force_n;    // 3n, or empty: none (gravity: lumped_masses_kg x g)
  std::vector<FemHalfSpace> supports;  // the node stays on the free side
  std::vector<FemConvexBody> bodies;   // the node stays outside
  double penalty_n_per_m = 1e4;        // per node; a node pressed with F sits F / k inside
};

struct FemSolveReport {
  bool converged = false;
  int newton_iterations = 0;  // over all load steps
  double residual_n = 0.0;    // largest free residual force at the end
};

class StaticFem {
 public:
  // throws std::invalid_argument on a node index out of range or a degenerate rest tet
  StaticFem(FemMesh mesh, const NeoHookean& material);

  int node_count() const { return static_cast<int>(mesh_.rest_m.cols()); }
  const FemMesh& mesh() const { return mesh_; }
  Eigen::VectorXd rest_positions() const;  // 3n, x0 y0 z0 x1 ...
  // each node's share of the mesh's mass (a quarter of each tet's), kg
  Eigen::VectorXd lumped_masses_kg(double density_kg_per_m3) const;

  // the elastic energy (J; +inf when a tet is inverted), its gradient (the negative of the
  // internal forces, N) and its Hessian (N/m), at positions x (3n)
  double energy(const Eigen::VectorXd& x) const;
  void gradient(const Eigen::VectorXd& x, Eigen::VectorXd* g) const;
  void stiffness(const Eigen::VectorXd& x, Eigen::SparseMatrix<double>* k) const;

  // solves for equilibrium; x: 3n, the start (the rest shape when empty) and the result. At the
  // end gradient(x) - f_ext at a prescribed DOF is its reaction force
  FemSolveReport solve(const FemBoundary& bc, Eigen::VectorXd* x, const FemSolveOptions& options = {}) const;

 private:
  FemMesh mesh_;
  NeoHookean material_;
  std::vector<Eigen::Matrix3d> rest_inverse_;  // D_m^-1 per tet
  std::vector<double> rest_volume_m3_;
};

}  // namespace pcisim::physics::fem
