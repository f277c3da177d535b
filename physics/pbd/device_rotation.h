#pragma once
// The CUDA twin of extract_rotation (rotation_extraction.h): the rotation R of the polar
// decomposition of M = A_pq + s R_prev with det R = +1, for one cluster in one device thread.
//
// One-sided (Hestenes) Jacobi: plane rotations V make the columns of W = M V orthogonal, so
// W = U Sigma. Only the two largest singular pairs are used: R = u1 v1^T + u2 v2^T + (u1 x u2)(v1 x v2)^T
// equals U diag(1, 1, det(U V^T)) V^T, the CPU's reflection fix on the thinnest axis, for any sign
// of det M, and is a proper rotation by construction. Agreement with Eigen's JacobiSVD: 3.7e-15
// per entry at worst over 2000 random, mirrored and stretched matrices (asserted 1e-12,
// tests/physics/pbd/device_twins_test.cc); on collinear or coincident clusters (sigma_2 of the
// order of the regulariser) the free axes are only good to ~1e-7 (asserted 1e-6).
#include "physics/pbd/device_math.h"

namespace pcisim::physics::pbd::device {

// Started from the plane rotations V that orthogonalised the columns last time (*right, in and
// out, orthonormal: M's right singular vectors change little between a cluster's solves, so its
// columns are nearly orthogonal already and a sweep or two finish them). An orthonormal start
// gives the cold start's R to rounding where R is unique; where it is not (sigma_2 ~ the
// regulariser: collinear or coincident clusters, the free axes good to ~1e-7 either way; or
// det M < 0 with sigma_2 = sigma_3) the two may differ by more. The identity is the cold start.
PCISIM_HD inline Mat3 extract_rotation_from(const Mat3& a, const Mat3& previous, double rest_moment_kg_m2,
                                            Mat3* right) {
  // same regulariser as the CPU (kRotationRegularisation = 1e-9)
  const double reg = 1e-9 * rest_moment_kg_m2;
  const double scale = reg > 1e-300 ? reg : 1e-300;
  Mat3 m;
  for (int k = 0; k < 9; ++k) m.m[k] = a.m[k] + scale * previous.m[k];
  Mat3 v;
  v(0, 0) = v(1, 1) = v(2, 2) = 1.0;
  if (!finite(m)) {
    *right = v;
    return previous;
  }
  // the start made orthonormal again (Gram-Schmidt: rounding drifts over many solves); W = M V
  {
    const Vec3 v1 = right->col(0) / norm(right->col(0));
    Vec3 v2 = right->col(1) - dot(v1, right->col(1)) * v1;
    v2 = v2 / norm(v2);
    const Vec3 v3 = cross(v1, v2);
    if (finite(v1) && finite(v2) && finite(v3)) {
      v.set_col(0, v1);
      v.set_col(1, v2);
      v.set_col(2, v3);
    }
  }
  Mat3 w;
  for (int col = 0; col < 3; ++col) w.set_col(col, m * v.col(col));
  constexpr int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int sweep = 0; sweep < 20; ++sweep) {
    bool rotated = false;
    for (const auto& pq : kPairs) {
      const int p = pq[0], q = pq[1];
      const Vec3 wp = w.col(p), wq = w.col(q);
      const double alpha = squared_norm(wp), beta = squared_norm(wq), gamma = dot(wp, wq);
      // orthogonal to rounding already
      if (!(std::fabs(gamma) > 1e-15 * std::sqrt(alpha * beta))) continue;
      rotated = true;
      const double zeta = (beta - alpha) / (2.0 * gamma);
      const double t = (zeta >= 0.0 ? 1.0 : -1.0) / (std::fabs(zeta) + std::sqrt(1.0 + zeta * zeta));
      const double c = 1.0 / std::sqrt(1.0 + t * t), s = c * t;
      w.set_col(p, c * wp - s * wq);
      w.set_col(q, s * wp + c * wq);
      const Vec3 vp = v.col(p), vq = v.col(q);
      v.set_col(p, c * vp - s * vq);
      v.set_col(q, s * vp + c * vq);
    }
    if (!rotated) break;
  }
  // the two largest singular values: sigma_i = |w_i|
  double sig[3];
  for (int k = 0; k < 3; ++k) sig[k] = squared_norm(w.col(k));
  int i1 = 0;
  for (int k = 1; k < 3; ++k)
    if (sig[k] > sig[i1]) i1 = k;
  int i2 = i1 == 0 ? 1 : 0;
  for (int k = 0; k < 3; ++k)
    if (k != i1 && sig[k] > sig[i2]) i2 = k;
  const Vec3 u1 = w.col(i1) / std::sqrt(sig[i1]);
  Vec3 u2 = w.col(i2) - dot(u1, w.col(i2)) * u1;  // re-orthogonalised against rounding
  u2 = u2 / norm(u2);
  const Vec3 v1 = v.col(i1), v2 = v.col(i2);
  const Vec3 u3 = cross(u1, u2), v3 = cross(v1, v2);
  Mat3 r;
  for (int col = 0; col < 3; ++col) {
    const double c1 = col == 0 ? v1.x : col == 1 ? v1.y : v1.z;
    const double c2 = col == 0 ? v2.x : col == 1 ? v2.y : v2.z;
    const double c3 = col == 0 ? v3.x : col == 1 ? v3.y : v3.z;
    r.set_col(col, c1 * u1 + c2 * u2 + c3 * u3);
  }
  if (!finite(r)) {
    Mat3 identity;
    identity(0, 0) = identity(1, 1) = identity(2, 2) = 1.0;
    *right = identity;
    return previous;
  }
  *right = v;
  return r;
}

// the cold start: the plane rotations from the identity
PCISIM_HD inline Mat3 extract_rotation(const Mat3& a, const Mat3& previous, double rest_moment_kg_m2) {
  Mat3 right;
  right(0, 0) = right(1, 1) = right(2, 2) = 1.0;
  return extract_rotation_from(a, previous, rest_moment_kg_m2, &right);
}

}  // namespace pcisim::physics::pbd::device
