#include "physics/pbd/dihedral_bending_constraint.h"

#include <cmath>
#include <numbers>

namespace pcisim::physics::pbd {

bool dihedral_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& d, double* theta_rad, Eigen::Vector3d grad[4]) {
  const Eigen::Vector3d e = b - a;
  const double e_len = e.norm();
  // area-weighted normals of (a, b, c) and (b, a, d)
  const Eigen::Vector3d n1 = (c - a).cross(c - b);
  const Eigen::Vector3d n2 = (d - b).cross(d - a);
  const double n1_sq = n1.squaredNorm(), n2_sq = n2.squaredNorm();
  // degenerate: zero-length edge or a sliver triangle (relative to the edge) has no normal
  const double tiny = 1e-24 * e_len * e_len * e_len * e_len;
  if (!(e_len > 1e-12) || !(n1_sq > tiny) || !(n2_sq > tiny)) return false;
  const Eigen::Vector3d u1 = n1 / std::sqrt(n1_sq), u2 = n2 / std::sqrt(n2_sq);
  *theta_rad = std::atan2(u1.cross(u2).dot(e / e_len), u1.dot(u2));
  // gradients of the dihedral angle (Bridson et al. 2003's bending modes, signed for atan2 above)
  const Eigen::Vector3d g1 = n1 / n1_sq, g2 = n2 / n2_sq;
  grad[2] = -e_len * g1;
  grad[3] = -e_len * g2;
  grad[0] = -((c - b).dot(e) / e_len) * g1 - ((d - b).dot(e) / e_len) * g2;
  grad[1] = ((c - a).dot(e) / e_len) * g1 + ((d - a).dot(e) / e_len) * g2;
  return true;
}

double wrapped_angle_error(double theta_rad, double rest_rad) {
  double c = theta_rad - rest_rad;
  constexpr double kPi = std::numbers::pi;
  while (c > kPi) c -= 2.0 * kPi;
  while (c <= -kPi) c += 2.0 * kPi;
  return c;
}

bool project_dihedral_bending(const Eigen::Vector3d x[4], const double w[4], double rest_angle_rad, double alpha_tilde,
                              double lambda, double* dlambda, Eigen::Vector3d dx[4]) {
  double theta = 0.0;
  Eigen::Vector3d g[4];
  if (!dihedral_angle(x[0], x[1], x[2], x[3], &theta, g)) return false;
  double denom = alpha_tilde;
  for (int k = 0; k < 4; ++k) denom += w[k] * g[k].squaredNorm();
  if (!(denom > 0.0)) return false;
  const double dl = (-wrapped_angle_error(theta, rest_angle_rad) - alpha_tilde * lambda) / denom;
  if (!std::isfinite(dl)) return false;
  *dlambda = dl;
  for (int k = 0; k < 4; ++k) dx[k] = (w[k] * dl) * g[k];
  return true;
}

}  // namespace pcisim::physics::pbd
