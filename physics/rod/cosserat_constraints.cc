#include "physics/rod/cosserat_constraints.h"

namespace pcisim::physics::rod {
namespace {

Eigen::Quaterniond pure(const Eigen::Vector3d& v) {
  return Eigen::Quaterniond(0.0, v.x(), v.y(), v.z());
}

void add_scaled(Eigen::Quaterniond& q, double s, const Eigen::Quaterniond& d) {
  q.coeffs() += s * d.coeffs();
}

// +1 or -1: the sign of q2 that makes the relative rotation the shorter one (w >= 0). The
// paper's rule (take the sign whose Darboux vector is nearer the rest value) fails for a rod
// with rest curvature near its rest state: there both signs give small vectors and the rule
// picks the one pointing along the rest curvature, so the strain is even in the bend and the
// energy has no gradient there (measured: a unit cantilever with a rest curvature of 1/m stayed
// straight in the static solve, converged, and its tip oscillated forever in the dynamic one)
double darboux_sign(const Eigen::Quaterniond& relative, double /*dual_length_m*/, const Eigen::Vector3d& /*rest*/) {
  return relative.w() >= 0.0 ? 1.0 : -1.0;
}

}  // namespace

Eigen::Vector3d stretch_shear_strain(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, const Eigen::Quaterniond& q,
                                     double rest_length_m) {
  const Eigen::Vector3d gamma_world = (p2 - p1) / rest_length_m - q * Eigen::Vector3d::UnitZ();
  return q.conjugate() * gamma_world;
}

Eigen::Vector3d bend_twist_strain(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2, double dual_length_m,
                                  const Eigen::Vector3d& rest_darboux_per_m) {
  const Eigen::Quaterniond relative = q1.conjugate() * q2;
  const double s = darboux_sign(relative, dual_length_m, rest_darboux_per_m);
  return s * (2.0 / dual_length_m) * relative.vec() - rest_darboux_per_m;
}

void project_stretch_shear(Eigen::Vector3d& p1, double w1, Eigen::Vector3d& p2, double w2, Eigen::Quaterniond& q,
                           double wq, double rest_length_m, const Eigen::Vector3d& alpha_tilde,
                           Eigen::Vector3d& lambda) {
  const double l = rest_length_m;
  const Eigen::Vector3d gamma = stretch_shear_strain(p1, p2, q, l);  // material frame
  // shear components (x, y) are taken up by the nodes and the rotation; the stretch component
  // (z, along d3) by the nodes alone: a unit quaternion cannot lengthen d3 (that gradient,
  // 2 d3 q e3^* = 2 q, points along q and the normalisation removes it)
  const double a_nodes = (w1 + w2) / (l * l);
  Eigen::Vector3d dlambda;
  for (int k = 0; k < 3; ++k) {
    const double a = k < 2 ? a_nodes + 4.0 * wq : a_nodes;
    dlambda[k] = -(gamma[k] + alpha_tilde[k] * lambda[k]) / (a + alpha_tilde[k]);
  }
  lambda += dlambda;
  const Eigen::Vector3d dlambda_world = q * dlambda;
  // an immovable body (w = 0) is not touched: 0 x NaN would still poison it
  if (w1 > 0.0) p1 -= (w1 / l) * dlambda_world;
  if (w2 > 0.0) p2 += (w2 / l) * dlambda_world;
  // dq = -2 wq (dlambda q e3^*), e3^* = -e3, with the shear part of dlambda only
  const Eigen::Quaterniond e3_conj(0.0, 0.0, 0.0, -1.0);
  const Eigen::Vector3d shear_world = q * Eigen::Vector3d(dlambda.x(), dlambda.y(), 0.0);
  if (wq > 0.0) {
    add_scaled(q, -2.0 * wq, pure(shear_world) * q * e3_conj);
    q.normalize();
  }
}

void project_bend_twist(Eigen::Quaterniond& q1, double w1, Eigen::Quaterniond& q2, double w2, double dual_length_m,
                        const Eigen::Vector3d& rest_darboux_per_m, const Eigen::Vector3d& alpha_tilde,
                        Eigen::Vector3d& lambda) {
  const double l = dual_length_m;
  const Eigen::Quaterniond relative = q1.conjugate() * q2;
  const double s = darboux_sign(relative, l, rest_darboux_per_m);
  const Eigen::Vector3d omega = s * (2.0 / l) * relative.vec() - rest_darboux_per_m;
  const double a = 4.0 * (w1 + w2) / (l * l);
  Eigen::Vector3d dlambda;
  for (int k = 0; k < 3; ++k) dlambda[k] = -(omega[k] + alpha_tilde[k] * lambda[k]) / (a + alpha_tilde[k]);
  lambda += dlambda;
  const Eigen::Quaterniond v = pure(dlambda);
  const Eigen::Quaterniond q1_old = q1;
  if (w1 > 0.0) {
    add_scaled(q1, -w1 * s * 2.0 / l, q2 * v);
    q1.normalize();
  }
  if (w2 > 0.0) {
    add_scaled(q2, w2 * s * 2.0 / l, q1_old * v);
    q2.normalize();
  }
}

Eigen::Matrix3d stretch_shear_rotation_jacobian(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d d3 = q * Eigen::Vector3d::UnitZ();
  Eigen::Matrix3d cross;
  cross << 0.0, -d3.z(), d3.y(), d3.z(), 0.0, -d3.x(), -d3.y(), d3.x(), 0.0;
  return cross;
}

Eigen::Matrix3d bend_twist_jacobian(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2, double dual_length_m,
                                    const Eigen::Vector3d& rest_darboux_per_m, Eigen::Vector3d* strain) {
  const double l = dual_length_m;
  const Eigen::Quaterniond relative = q1.conjugate() * q2;
  const double s = darboux_sign(relative, l, rest_darboux_per_m);
  *strain = s * (2.0 / l) * relative.vec() - rest_darboux_per_m;
  // Im((0, a) (w, v)) = w a + a x v = (w I - [v]x) a, with a = R1^T dtheta / 2
  const Eigen::Vector3d v = relative.vec();
  Eigen::Matrix3d m = relative.w() * Eigen::Matrix3d::Identity();
  m(0, 1) += v.z();
  m(0, 2) -= v.y();
  m(1, 0) -= v.z();
  m(1, 2) += v.x();
  m(2, 0) += v.y();
  m(2, 1) -= v.x();
  return (s / l) * m * q1.toRotationMatrix().transpose();
}

}  // namespace pcisim::physics::rod
