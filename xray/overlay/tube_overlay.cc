#include "xray/overlay/tube_overlay.h"

#include <algorithm>
#include <cmath>

#include "xray/overlay/cone_chord.h"

namespace pcisim::xray {

bool cone_shadow_box(const DetectorGeometry& g, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double ra_mm,
                     double rb_mm, std::array<int, 4>* box) {
  Eigen::Vector2d pa, pb;
  if (!g.project(a, &pa) || !g.project(b, &pb)) return false;
  const Eigen::Vector3d n = g.normal();
  const double sid = n.dot(g.center_mm - g.source_mm);
  // the shadow's half-width in pixels: the larger radius magnified at the nearer end, plus a pixel
  const double depth = std::min(n.dot(a - g.source_mm), n.dot(b - g.source_mm));
  const double margin = std::max(ra_mm, rb_mm) * sid / depth / g.pixel_mm + 1.0;
  const double cl = std::min(pa.x(), pb.x()) - margin, ch = std::max(pa.x(), pb.x()) + margin;
  const double rl = std::min(pa.y(), pb.y()) - margin, rh = std::max(pa.y(), pb.y()) + margin;
  // !(x >= lo) also catches NaN; bounds are clamped in double before the cast to int, so a point
  // near the source plane (a huge shadow) or far out cannot overflow it
  if (!(ch >= 0) || !(rh >= 0) || !(cl <= g.width - 1) || !(rl <= g.height - 1)) return false;
  (*box)[0] = static_cast<int>(std::max(0.0, std::floor(cl)));
  (*box)[1] = static_cast<int>(std::min(g.width - 1.0, std::ceil(ch)));
  (*box)[2] = static_cast<int>(std::max(0.0, std::floor(rl)));
  (*box)[3] = static_cast<int>(std::min(g.height - 1.0, std::ceil(rh)));
  return true;
}

void add_cone_segment(const DetectorGeometry& g, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double ra_mm,
                      double rb_mm, double mu_per_mm, Image* image) {
  ConeChord cone;
  if (!cone.set(g.source_mm, a, b, ra_mm, rb_mm)) return;
  std::array<int, 4> box;
  if (!cone_shadow_box(g, a, b, ra_mm, rb_mm, &box)) return;
  const int c0 = box[0], c1 = box[1], r0 = box[2], r1 = box[3];
  const Eigen::Vector3d du = g.pixel_mm * g.u;
  const float mu = static_cast<float>(mu_per_mm);
  for (int r = r0; r <= r1; ++r) {
    // ray direction to the row's first pixel, then one pixel step along u at a time
    Eigen::Vector3d d = g.pixel_center_mm(c0, r) - g.source_mm;
    float* row = image->pixels.data() + static_cast<size_t>(r) * image->width;
    for (int c = c0; c <= c1; ++c, d += du) {
      const double l = cone.chord_mm(d);
      if (l > 0) row[c] += mu * static_cast<float>(l);
    }
  }
}

}  // namespace pcisim::xray
