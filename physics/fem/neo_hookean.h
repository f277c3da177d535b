#pragma once
// The compressible neo-Hookean material of the reference FEM (issue #16 item 5: the independent
// ground truth the tissue's cluster stiffness is calibrated against). Strain energy per unit rest
// volume, first Piola-Kirchhoff stress and its directional derivative:
//   psi(F) = mu/2 (tr(F^T F) - 3) - mu ln J + lambda/2 (ln J)^2,   J = det F
//   P(F)   = mu (F - F^-T) + lambda ln J F^-T
//   dP     = mu dF + (mu - lambda ln J) F^-T dF^T F^-T + lambda tr(F^-1 dF) F^-T
// (Bonet & Wood, "Nonlinear continuum mechanics for finite element analysis", 2nd ed., 2008,
// sec. 6.4.3; Sifakis & Barbic, "FEM simulation of 3D deformable solids", SIGGRAPH 2012 course).
#include <Eigen/Core>

namespace pcisim::physics::fem {

struct NeoHookean {
  double mu_pa = 0.0;      // shear modulus
  double lambda_pa = 0.0;  // first Lame parameter
};

// from Young's modulus and Poisson's ratio (0 < E, -1 < nu < 0.5); throws std::invalid_argument
NeoHookean neo_hookean_from_young(double young_pa, double poisson);

// +inf when J <= 0 (an inverted element has no energy in this model: the solver backs off)
double energy_density(const NeoHookean& m, const Eigen::Matrix3d& f);
Eigen::Matrix3d first_piola(const NeoHookean& m, const Eigen::Matrix3d& f);
Eigen::Matrix3d first_piola_differential(const NeoHookean& m, const Eigen::Matrix3d& f, const Eigen::Matrix3d& df);

}  // namespace pcisim::physics::fem
