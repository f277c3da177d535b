#include "xray/overlay/wire_overlay.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace pcisim::xray {

namespace {

// chord length (mm) of the segment s -> p through the cylinder of radius r about a -> a + len w
double chord_mm(const Eigen::Vector3d& s, const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                const Eigen::Vector3d& w, double len, double r) {
  const Eigen::Vector3d d = p - s, m = s - a;
  const double dw = d.dot(w), mw = m.dot(w);
  const Eigen::Vector3d dp = d - dw * w, mp = m - mw * w;
  const double qa = dp.squaredNorm(), qb = mp.dot(dp), qc = mp.squaredNorm() - r * r;
  if (qa < 1e-18) return 0.0;  // ray parallel to the axis: a wire seen end-on, ignored
  const double disc = qb * qb - qa * qc;
  if (disc <= 0) return 0.0;
  const double root = std::sqrt(disc);
  double t0 = (-qb - root) / qa, t1 = (-qb + root) / qa;
  // between the end planes of the cylinder
  if (std::abs(dw) < 1e-18) {
    if (mw < 0 || mw > len) return 0.0;
  } else {
    double u0 = -mw / dw, u1 = (len - mw) / dw;
    if (u0 > u1) std::swap(u0, u1);
    t0 = std::max(t0, u0);
    t1 = std::min(t1, u1);
  }
  t0 = std::max(t0, 0.0);
  t1 = std::min(t1, 1.0);
  return t1 > t0 ? (t1 - t0) * d.norm() : 0.0;
}

}  // namespace

void add_wire(const DetectorGeometry& g, const std::vector<Eigen::Vector3d>& wire_mm, const WireSpec& wire,
              Image* image) {
  const Eigen::Vector3d n = g.normal();
  const double sid = n.dot(g.center_mm - g.source_mm);
  for (size_t k = 0; k + 1 < wire_mm.size(); ++k) {
    const Eigen::Vector3d a = wire_mm[k], b = wire_mm[k + 1];
    const double len = (b - a).norm();
    if (!(len > 0)) continue;
    const Eigen::Vector3d w = (b - a) / len;
    Eigen::Vector2d pa, pb;
    if (!g.project(a, &pa) || !g.project(b, &pb)) continue;
    // the shadow's half-width in pixels: the radius magnified at the nearer end, plus a pixel
    const double depth = std::min(n.dot(a - g.source_mm), n.dot(b - g.source_mm));
    const double margin = wire.radius_mm * sid / depth / g.pixel_mm + 1.0;
    const int c0 = std::max(0, static_cast<int>(std::floor(std::min(pa.x(), pb.x()) - margin)));
    const int c1 = std::min(g.width - 1, static_cast<int>(std::ceil(std::max(pa.x(), pb.x()) + margin)));
    const int r0 = std::max(0, static_cast<int>(std::floor(std::min(pa.y(), pb.y()) - margin)));
    const int r1 = std::min(g.height - 1, static_cast<int>(std::ceil(std::max(pa.y(), pb.y()) + margin)));
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        const double l = chord_mm(g.source_mm, g.pixel_center_mm(c, r), a, w, len, wire.radius_mm);
        if (l > 0) image->at(c, r) += static_cast<float>(wire.mu_per_mm * l);
      }
    }
  }
}

void project_polyline(const DetectorGeometry& g, const std::vector<Eigen::Vector3d>& points_mm,
                      std::vector<Eigen::Vector2d>* pixels) {
  pixels->resize(points_mm.size());
  for (size_t k = 0; k < points_mm.size(); ++k) {
    if (!g.project(points_mm[k], &(*pixels)[k])) {
      (*pixels)[k].setConstant(std::numeric_limits<double>::quiet_NaN());
    }
  }
}

}  // namespace pcisim::xray
