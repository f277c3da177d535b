#pragma once
// Closed-form chord of a ray through a truncated cone (a lumen segment whose radius changes
// linearly from ra to rb; a cylinder when ra == rb), with everything that depends only on the
// segment and the source precomputed so a pixel costs three dot products and a square root.
// Shared by the wire and the contrast overlays. No end caps: consecutive segments of a gently
// bending tube neither double nor visibly gap at their joints.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace pcisim::xray {

class ConeChord {
 public:
  // source s, axis from a to b (mm), radii ra at a and rb at b; false for a zero-length axis
  bool set(const Eigen::Vector3d& s, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double ra, double rb) {
    len_ = (b - a).norm();
    if (!(len_ > 0)) return false;
    w_ = (b - a) / len_;
    const Eigen::Vector3d m = s - a;
    mw_ = m.dot(w_);
    mp_ = m - mw_ * w_;
    mp2_ = mp_.squaredNorm();
    k_ = (rb - ra) / len_;  // radius slope along the axis
    r0_ = ra + k_ * mw_;    // radius of the cone's plane through the source
    rmean_ = 0.5 * (ra + rb);
    return true;
  }

  // chord length (mm) of the segment from the source to s + d (d: source -> pixel centre)
  double chord_mm(const Eigen::Vector3d& d) const {
    const double dd = d.squaredNorm(), dw = d.dot(w_), qb = mp_.dot(d);
    const double qa = dd - dw * dw;   // |d projected off the axis|^2
    if (qa < 1e-18 * dd) return 0.0;  // seen end-on: ignored
    // |mp + t dp|^2 = (r0 + k dw t)^2, a quadratic A t^2 + 2 B t + C = 0
    double kk = k_ * dw, r0 = r0_;
    double qa2 = qa - kk * kk;
    if (qa2 <= 1e-6 * qa) {  // the ray runs inside the cone's half-angle: use the mean radius
      kk = 0;
      r0 = rmean_;
      qa2 = qa;
    }
    const double b = qb - r0 * kk, c = mp2_ - r0 * r0;
    const double disc = b * b - qa2 * c;
    if (disc <= 0) return 0.0;
    const double root = std::sqrt(disc);
    double t0 = (-b - root) / qa2, t1 = (-b + root) / qa2;
    // between the end planes
    if (std::abs(dw) < 1e-18) {
      if (mw_ < 0 || mw_ > len_) return 0.0;
    } else {
      double u0 = -mw_ / dw, u1 = (len_ - mw_) / dw;
      if (u0 > u1) std::swap(u0, u1);
      t0 = std::max(t0, u0);
      t1 = std::min(t1, u1);
    }
    t0 = std::max(t0, 0.0);
    t1 = std::min(t1, 1.0);
    return t1 > t0 ? (t1 - t0) * std::sqrt(dd) : 0.0;
  }

 private:
  Eigen::Vector3d w_, mp_;
  double len_ = 0, mw_ = 0, mp2_ = 0, k_ = 0, r0_ = 0, rmean_ = 0;
};

}  // namespace pcisim::xray
