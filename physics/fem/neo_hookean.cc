#include "physics/fem/neo_hookean.h"

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace pcisim::physics::fem {

NeoHookean neo_hookean_from_young(double young_pa, double poisson) {
  if (!(young_pa > 0.0) || !std::isfinite(young_pa) || !(poisson > -1.0 && poisson < 0.5))
    throw std::invalid_argument("neo-Hookean: Young's modulus must be positive and Poisson's ratio in (-1, 0.5)");
  // mu = E / (2 (1 + nu)), lambda = E nu / ((1 + nu)(1 - 2 nu))
  return {young_pa / (2.0 * (1.0 + poisson)), young_pa * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson))};
}

double energy_density(const NeoHookean& m, const Eigen::Matrix3d& f) {
  const double j = f.determinant();
  if (!(j > 0.0)) return std::numeric_limits<double>::infinity();
  const double log_j = std::log(j);
  return 0.5 * m.mu_pa * (f.squaredNorm() - 3.0) - m.mu_pa * log_j + 0.5 * m.lambda_pa * log_j * log_j;
}

Eigen::Matrix3d first_piola(const NeoHookean& m, const Eigen::Matrix3d& f) {
  const Eigen::Matrix3d f_inv_t = f.inverse().transpose();
  return m.mu_pa * (f - f_inv_t) + m.lambda_pa * std::log(f.determinant()) * f_inv_t;
}

Eigen::Matrix3d first_piola_differential(const NeoHookean& m, const Eigen::Matrix3d& f, const Eigen::Matrix3d& df) {
  const Eigen::Matrix3d f_inv = f.inverse();
  const Eigen::Matrix3d f_inv_t = f_inv.transpose();
  const double log_j = std::log(f.determinant());
  return m.mu_pa * df + (m.mu_pa - m.lambda_pa * log_j) * f_inv_t * df.transpose() * f_inv_t +
         m.lambda_pa * (f_inv * df).trace() * f_inv_t;
}

}  // namespace pcisim::physics::fem
