#pragma once
// Distance constraint C = |x_i - x_j| - d0 with XPBD compliance (a spring of stiffness 1/alpha).
#include <Eigen/Core>
#include <cmath>

namespace pcisim::physics::pbd {

struct DistanceConstraint {
  int i = 0, j = 0;
  double rest_m = 0.0;
  double compliance_m_per_n = 0.0;  // alpha; 0 = inextensible
};

// below this the direction i->j is undefined and the constraint waits (shape matching separates)
inline constexpr double kMinDistanceM = 1e-12;

// One projection. Soft-tissue paper eqs 3-5 (heart paper eqs 5-6): dx = M^-1 grad C^T dlambda,
// with the XPBD compliance term: dlambda = (-C - alpha~ lambda) / (w_i + w_j + alpha~),
// alpha~ = alpha / dt^2. Returns false (and leaves outputs alone) when there is nothing finite to do.
inline bool project_distance(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj, double wi, double wj, double rest_m,
                             double alpha_tilde, double lambda, double* dlambda, Eigen::Vector3d* dxi,
                             Eigen::Vector3d* dxj) {
  const Eigen::Vector3d d = xi - xj;
  const double len = d.norm();
  const double denom = wi + wj + alpha_tilde;
  if (!(len > kMinDistanceM) || !(denom > 0.0)) return false;
  const Eigen::Vector3d n = d / len;  // grad_i C = n, grad_j C = -n
  const double dl = (-(len - rest_m) - alpha_tilde * lambda) / denom;
  if (!std::isfinite(dl)) return false;
  *dlambda = dl;
  *dxi = (wi * dl) * n;
  *dxj = (-wj * dl) * n;
  return true;
}

}  // namespace pcisim::physics::pbd
