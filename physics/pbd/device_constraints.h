#pragma once
// The constraint projections of distance_constraint.h, dihedral_bending_constraint.h and
// shape_matching_clusters.h (project_to_goal) on device::Vec3, in the same order of operations,
// for the CUDA Jacobi solver; tests/physics/pbd/ checks them against the Eigen originals.
#include <numbers>

#include "physics/pbd/device_math.h"

namespace pcisim::physics::pbd::device {

// soft-tissue paper eqs 3-5 with XPBD compliance (see project_distance)
PCISIM_HD inline bool project_distance(Vec3 xi, Vec3 xj, double wi, double wj, double rest_m, double alpha_tilde,
                                       double lambda, double* dlambda, Vec3* dxi, Vec3* dxj) {
  const Vec3 d = xi - xj;
  const double len = norm(d);
  const double denom = wi + wj + alpha_tilde;
  if (!(len > 1e-12) || !(denom > 0.0)) return false;  // kMinDistanceM
  const Vec3 n = d / len;
  const double dl = (-(len - rest_m) - alpha_tilde * lambda) / denom;
  if (!std::isfinite(dl)) return false;
  *dlambda = dl;
  *dxi = (wi * dl) * n;
  *dxj = (-wj * dl) * n;
  return true;
}

// see dihedral_angle: hinge a-b, wings c, d
PCISIM_HD inline bool dihedral_angle(Vec3 a, Vec3 b, Vec3 c, Vec3 d, double* theta_rad, Vec3 grad[4]) {
  const Vec3 e = b - a;
  const double e_len = norm(e);
  const Vec3 n1 = cross(c - a, c - b);
  const Vec3 n2 = cross(d - b, d - a);
  const double n1_sq = squared_norm(n1), n2_sq = squared_norm(n2);
  const double tiny = 1e-24 * e_len * e_len * e_len * e_len;
  if (!(e_len > 1e-12) || !(n1_sq > tiny) || !(n2_sq > tiny)) return false;
  const Vec3 u1 = n1 / std::sqrt(n1_sq), u2 = n2 / std::sqrt(n2_sq);
  *theta_rad = std::atan2(dot(cross(u1, u2), e / e_len), dot(u1, u2));
  const Vec3 g1 = n1 / n1_sq, g2 = n2 / n2_sq;
  grad[2] = -e_len * g1;
  grad[3] = -e_len * g2;
  grad[0] = (-(dot(c - b, e) / e_len)) * g1 - (dot(d - b, e) / e_len) * g2;
  grad[1] = (dot(c - a, e) / e_len) * g1 + (dot(d - a, e) / e_len) * g2;
  return true;
}

PCISIM_HD inline double wrapped_angle_error(double theta_rad, double rest_rad) {
  double c = theta_rad - rest_rad;
  constexpr double kPi = std::numbers::pi;
  while (c > kPi) c -= 2.0 * kPi;
  while (c <= -kPi) c += 2.0 * kPi;
  return c;
}

PCISIM_HD inline bool project_dihedral_bending(const Vec3 x[4], const double w[4], double rest_angle_rad,
                                               double alpha_tilde, double lambda, double* dlambda, Vec3 dx[4]) {
  double theta = 0.0;
  Vec3 g[4];
  if (!dihedral_angle(x[0], x[1], x[2], x[3], &theta, g)) return false;
  double denom = alpha_tilde;
  for (int k = 0; k < 4; ++k) denom += w[k] * squared_norm(g[k]);
  if (!(denom > 0.0)) return false;
  const double dl = (-wrapped_angle_error(theta, rest_angle_rad) - alpha_tilde * lambda) / denom;
  if (!std::isfinite(dl)) return false;
  *dlambda = dl;
  for (int k = 0; k < 4; ++k) dx[k] = (w[k] * dl) * g[k];
  return true;
}

// soft-tissue paper eq 12 as XPBD C = x - g, compliance scaled by 1/m (see project_to_goal)
PCISIM_HD inline bool project_to_goal(Vec3 x, Vec3 goal, double w, double mass_kg, double compliance_s2, double dt_s,
                                      Vec3 lambda, Vec3* dlambda, Vec3* dx) {
  const double alpha_tilde = compliance_s2 / (mass_kg * dt_s * dt_s);
  const double denom = w + alpha_tilde;
  if (!(denom > 0.0)) return false;
  const Vec3 dl = (goal - x - alpha_tilde * lambda) / denom;
  if (!finite(dl)) return false;
  *dlambda = dl;
  *dx = w * dl;
  return true;
}

}  // namespace pcisim::physics::pbd::device
