#include "anatomy/phantom/thorax_phantom.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

#include "anatomy/phantom/coronary_phantom.h"

namespace pcisim::anatomy {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
constexpr double kDeg = std::numbers::pi / 180.0;

// seeded draws without std distributions (their output differs between standard libraries)
class Draw {
 public:
  explicit Draw(uint32_t seed) : rng_(seed ^ 0x9e3779b9u) {}
  double around(double value, double spread) {
    return value + spread * ((static_cast<double>(rng_() >> 8) / double(1u << 24)) * 2.0 - 1.0);
  }

 private:
  std::mt19937 rng_;
};

// a region painted by spans along x: inside when |m (p - c)|^2 <= 1 and z_lo <= z <= z_hi.
// An ellipsoid has a full-rank m; an elliptic cylinder along z has a zero third column.
struct Quadric {
  Matrix3d m;
  Vector3d c;
  double z_lo = -1e30, z_hi = 1e30;
  int16_t hu;
  // and, when clipped, inside the ellipsoid |clip_m (p - clip_c)|^2 <= 1
  bool clipped = false;
  Matrix3d clip_m = Matrix3d::Zero();
  Vector3d clip_c = Vector3d::Zero();
};

Quadric ellipsoid(const Vector3d& c, const Vector3d& semi, const Matrix3d& axes, double hu) {
  Quadric q;
  q.m = semi.cwiseInverse().asDiagonal() * axes.transpose();
  q.c = c;
  q.hu = static_cast<int16_t>(std::lround(hu));
  return q;
}

Quadric cylinder_z(double cx, double cy, double ax, double ay, double z_lo, double z_hi, double hu) {
  Quadric q;
  q.m.setZero();
  q.m(0, 0) = 1.0 / ax;
  q.m(1, 1) = 1.0 / ay;
  q.c = Vector3d(cx, cy, 0);
  q.z_lo = z_lo;
  q.z_hi = z_hi;
  q.hu = static_cast<int16_t>(std::lround(hu));
  return q;
}

// a tube as a chain of rounded cones (capsules with a radius varying along each segment)
struct Tube {
  std::vector<Vector3d> p_mm;
  std::vector<double> r_mm;
  int16_t hu;
};

class Painter {
 public:
  Painter(Volume* v) : v_(v) {}

  // the voxels [i0, i1] of row (j, k) inside |m (p - c)|^2 <= 1; false when none
  bool x_span(const Matrix3d& m, const Vector3d& c, int64_t j, int64_t k, int64_t* i0, int64_t* i1) const {
    const double z = v_->origin_mm.z() + k * v_->spacing_mm.z();
    const double y = v_->origin_mm.y() + j * v_->spacing_mm.y();
    const double x0 = v_->origin_mm.x();
    // |q0 + x m_x|^2 <= 1 with q0 at x = x0
    const Vector3d q0 = m * (Vector3d(x0, y, z) - c);
    const Vector3d mx = m.col(0);
    const double a = mx.squaredNorm(), b = q0.dot(mx), cc = q0.squaredNorm() - 1.0;
    *i0 = 0;
    *i1 = v_->dims[0] - 1;
    if (a < 1e-18) return cc <= 0;
    const double disc = b * b - a * cc;
    if (disc < 0) return false;
    const double s = std::sqrt(disc);
    // mm from x0 to voxel indices, clamped before the cast so no double overflows an int
    const double n = static_cast<double>(v_->dims[0]);
    const double t0 = std::clamp(std::ceil((-b - s) / a / v_->spacing_mm.x()), -1.0, n);
    const double t1 = std::clamp(std::floor((-b + s) / a / v_->spacing_mm.x()), -1.0, n);
    *i0 = std::max<int64_t>(0, static_cast<int64_t>(t0));
    *i1 = std::min<int64_t>(v_->dims[0] - 1, static_cast<int64_t>(t1));
    return *i0 <= *i1;
  }

  // fills the x-span of q on row (j, k); the row pointer is the volume's row
  void span(const Quadric& q, int64_t j, int64_t k) const {
    const double z = v_->origin_mm.z() + k * v_->spacing_mm.z();
    if (z < q.z_lo || z > q.z_hi) return;
    int64_t i0, i1;
    if (!x_span(q.m, q.c, j, k, &i0, &i1)) return;
    if (q.clipped) {
      int64_t c0, c1;
      if (!x_span(q.clip_m, q.clip_c, j, k, &c0, &c1)) return;
      i0 = std::max(i0, c0);
      i1 = std::min(i1, c1);
    }
    if (i1 < i0) return;
    int16_t* row = v_->hu_i16.data() + v_->linear_index(0, j, k);
    std::fill(row + i0, row + i1 + 1, q.hu);
  }

  // voxels of slab [k_lo, k_hi) within the tube
  void tube(const Tube& t, int64_t k_lo, int64_t k_hi) const {
    const Vector3d o = v_->origin_mm, s = v_->spacing_mm;
    for (size_t n = 0; n + 1 < t.p_mm.size(); ++n) {
      const Vector3d a = t.p_mm[n], b = t.p_mm[n + 1];
      const double ra = t.r_mm[n], rb = t.r_mm[n + 1], rmax = std::max(ra, rb);
      const Vector3d pad = Vector3d::Constant(rmax);
      const Vector3d lo = a.cwiseMin(b) - pad, hi = a.cwiseMax(b) + pad;
      int64_t ib[2][3];
      bool empty = false;
      for (int ax = 0; ax < 3; ++ax) {
        const double n = static_cast<double>(v_->dims[ax]);
        ib[0][ax] =
            std::max<int64_t>(0, static_cast<int64_t>(std::clamp(std::ceil((lo[ax] - o[ax]) / s[ax]), -1.0, n)));
        ib[1][ax] = std::min<int64_t>(v_->dims[ax] - 1,
                                      static_cast<int64_t>(std::clamp(std::floor((hi[ax] - o[ax]) / s[ax]), -1.0, n)));
        if (ib[1][ax] < ib[0][ax]) empty = true;
      }
      ib[0][2] = std::max(ib[0][2], k_lo);
      ib[1][2] = std::min(ib[1][2], k_hi - 1);
      if (empty || ib[1][2] < ib[0][2]) continue;
      const Vector3d ab = b - a;
      const double len2 = std::max(ab.squaredNorm(), 1e-12);
      for (int64_t k = ib[0][2]; k <= ib[1][2]; ++k) {
        for (int64_t j = ib[0][1]; j <= ib[1][1]; ++j) {
          int16_t* row = v_->hu_i16.data() + v_->linear_index(0, j, k);
          const Vector3d pj(o.x(), o.y() + j * s.y(), o.z() + k * s.z());
          for (int64_t i = ib[0][0]; i <= ib[1][0]; ++i) {
            const Vector3d ap = Vector3d(pj.x() + i * s.x(), pj.y(), pj.z()) - a;
            const double u = std::clamp(ap.dot(ab) / len2, 0.0, 1.0);
            const double r = ra + (rb - ra) * u;
            if ((ap - u * ab).squaredNorm() <= r * r) row[i] = t.hu;
          }
        }
      }
    }
  }

 private:
  Volume* v_;
};

int16_t to_hu(double v) {
  return static_cast<int16_t>(std::lround(std::clamp(v, -1024.0, 3071.0)));
}

}  // namespace

Volume make_thorax_phantom(const ThoraxPhantomSpec& spec) {
  return make_thorax_phantom(spec, make_coronary_phantom({.seed = spec.seed}));
}

Volume make_thorax_phantom(const ThoraxPhantomSpec& spec, const VesselTree& tree) {
  const ThoraxTissueHu& hu = spec.hu;
  Draw draw(spec.seed);

  // thorax outline (elliptic cylinder along z): ~320 x 230 mm, the heart left and anterior of
  // its centre (adult chest CT proportions)
  const double bx = draw.around(-15, 4), by = draw.around(32, 3);
  const double ax = draw.around(160, 8), ay = draw.around(115, 5);
  const double fat_mm = draw.around(12, 3);

  const Vector3d center_mm = spec.center_mm.allFinite() ? spec.center_mm : Vector3d(bx, by, 20.0);
  const Vector3d spacing = spec.spacing_xyz_mm.allFinite() ? spec.spacing_xyz_mm : Vector3d::Constant(spec.spacing_mm);
  const Vector3d half((spec.dims[0] - 1) * 0.5, (spec.dims[1] - 1) * 0.5, (spec.dims[2] - 1) * 0.5);
  Volume v = Volume::make(spec.dims, spacing, center_mm - spacing.cwiseProduct(half), VoxelType::kInt16);
  std::fill(v.hu_i16.begin(), v.hu_i16.end(), to_hu(hu.air));

  // the heart frame of the coronary phantom (docs/anatomy.md): base toward right, posterior, up
  const Vector3d base = Vector3d(-0.45, 0.35, 0.82).normalized();
  const Vector3d toward_front(0.0, -1.0, 0.0);
  Vector3d anterior = toward_front - base.dot(toward_front) * base;
  anterior.normalize();
  Matrix3d heart;  // columns: anterior, left, base
  heart.col(0) = anterior;
  heart.col(1) = base.cross(anterior);
  heart.col(2) = base;
  // the heart's pose (identity and 1 by default, which leave every product exact)
  heart = spec.heart_rotation * heart;
  const double k = spec.heart_scale;
  const Vector3d shape = spec.heart_axes_scale;
  auto in_heart = [&heart, &shape, k](double a, double l, double b) -> Vector3d {
    return heart * shape.cwiseProduct(Vector3d(a, l, b)) * k;
  };
  // an ellipsoid of the heart, its semi-axes (mm, heart frame) shaped and scaled
  auto heart_ellipsoid = [&heart, &shape, k](const Vector3d& c, const Vector3d& semi, double hu_value) {
    return ellipsoid(c, semi.cwiseProduct(shape) * k, heart, hu_value);
  };
  const double heart_r = kPhantomHeartRadiusMm;
  auto blood_or = [&hu](double v) { return std::isnan(v) ? hu.blood : v; };

  std::vector<Quadric> q;
  q.push_back(cylinder_z(bx, by, ax, ay, -1e30, 1e30, hu.fat));
  q.push_back(cylinder_z(bx, by + 2, ax - fat_mm, ay - fat_mm * 0.8, -1e30, 1e30, hu.muscle));
  // lungs: right larger, left with the cardiac notch (the heart is painted over it)
  q.push_back(
      ellipsoid(Vector3d(bx - draw.around(72, 4), by + 8, 15), Vector3d(62, 82, 125), Matrix3d::Identity(), hu.lung));
  q.push_back(
      ellipsoid(Vector3d(bx + draw.around(78, 4), by + 12, 12), Vector3d(58, 78, 120), Matrix3d::Identity(), hu.lung));
  // mediastinal soft tissue between the lungs, in front of the spine
  q.push_back(cylinder_z(bx + 5, by - 10, 28, 60, -1e30, 1e30, hu.soft_tissue));
  // liver dome under the right hemidiaphragm
  q.push_back(ellipsoid(Vector3d(bx - 35, by - 5, -150), Vector3d(135, 105, 88), Matrix3d::Identity(), hu.liver));
  // heart: pericardial fat, myocardium, chambers (heart frame offsets in mm)
  q.push_back(heart_ellipsoid(Vector3d::Zero(), Vector3d(55, 55, 56), hu.fat));
  q.push_back(heart_ellipsoid(Vector3d::Zero(), Vector3d(heart_r, heart_r, heart_r), hu.myocardium));
  const Vector3d lv_center = in_heart(-2, 14, -8);
  const size_t first_chamber = q.size();
  const Vector3d rv_semi = spec.rv_semi_mm.allFinite() ? spec.rv_semi_mm : Vector3d(11, 24, 28);
  q.push_back(heart_ellipsoid(lv_center, Vector3d(17, 17, 30), blood_or(spec.lv_hu)));             // LV
  q.push_back(heart_ellipsoid(in_heart(20, -10, -8), rv_semi, blood_or(spec.rv_hu)));              // RV
  q.push_back(heart_ellipsoid(in_heart(-22, 8, 26), Vector3d(15, 18, 14), blood_or(spec.la_hu)));  // LA
  q.push_back(heart_ellipsoid(in_heart(2, -26, 22), Vector3d(16, 15, 17), blood_or(spec.ra_hu)));  // RA
  // the atria and the right ventricle reach the epicardial surface as ellipsoids; a real chamber's
  // blood stays behind its wall and the epicardial fat the coronaries run in: each chamber clipped
  // to the myocardium's outline moved in by its wall
  const double rv_wall = std::isnan(spec.rv_wall_mm) ? spec.chamber_clearance_mm : spec.rv_wall_mm;
  for (size_t c = first_chamber; c < q.size(); ++c) {
    const double wall = c == first_chamber + 1 ? rv_wall : spec.chamber_clearance_mm;
    if (!(wall > 0)) continue;
    q[c].clipped = true;
    q[c].clip_m = (heart_r * k * shape - Vector3d::Constant(wall)).cwiseInverse().asDiagonal() * heart.transpose();
  }
  // sternum
  q.push_back(cylinder_z(bx + 4, by - ay + fat_mm + 9, 15, 7, -60, 110, hu.sternum));
  // spine: vertebral bodies (cortex, cancellous core), discs, neural arch, canal, spinous process
  const double sx = bx + 2, sy = by + draw.around(50, 3);
  const double period = 27.0, body_h = 22.0;
  for (double zc = -200; zc < 250; zc += period) {
    const double lo = zc - body_h / 2, hi = zc + body_h / 2;
    q.push_back(cylinder_z(sx, sy, 21, 17, hi, hi + period - body_h, hu.disc));
    q.push_back(cylinder_z(sx, sy, 21, 17, lo, hi, hu.cortical_bone));
    q.push_back(cylinder_z(sx, sy, 18.5, 14.5, lo + 1.5, hi - 1.5, hu.cancellous_bone));
    q.push_back(cylinder_z(sx, sy + 29, 17, 13, lo - 2, hi - 2, hu.rib));
    q.push_back(ellipsoid(Vector3d(sx, sy + 50, zc - 6), Vector3d(5, 17, 9), Matrix3d::Identity(), hu.rib));
  }
  q.push_back(cylinder_z(sx, sy + 29, 8, 8, -1e30, 1e30, hu.csf));

  std::vector<Tube> tubes;
  // ribs: from the transverse processes around the chest wall, sloping down toward the front,
  // then costal cartilage to the sternum's edge
  for (int n = 0; n < 12; ++n) {
    const double z0 = 175 - n * draw.around(24, 1.5);
    for (int side = -1; side <= 1; side += 2) {
      Tube bone{{}, {}, to_hu(hu.rib)}, cartilage{{}, {}, to_hu(hu.cartilage)};
      const double drop = draw.around(55, 8), th0 = 14 * kDeg, th1 = draw.around(128, 6) * kDeg, th2 = 168 * kDeg;
      const double rx = ax - fat_mm - 12, ry = ay - fat_mm - 10;
      for (double th = th0; th <= th2 + 1e-9; th += 4 * kDeg) {
        const double f = (th - th0) / (th1 - th0);
        const Vector3d p(bx + side * rx * std::sin(th), by + 2 + ry * std::cos(th),
                         z0 - drop * std::min(f, 1.0) + (f > 1 ? 12 * (f - 1) : 0.0));
        if (th <= th1 + 1e-9) {
          bone.p_mm.push_back(p);
          bone.r_mm.push_back(5.0);
        }
        if (th >= th1 - 4.5 * kDeg) {
          cartilage.p_mm.push_back(p);
          cartilage.r_mm.push_back(4.5);
        }
      }
      tubes.push_back(std::move(bone));
      tubes.push_back(std::move(cartilage));
    }
  }
  // epicardial fat sleeves, then the coronary lumens, then the outflow tract and the aorta over
  // them (the LM and RCA start on the aortic centerline)
  auto coronary_tubes = [&](double hu_value, double pad_mm) {
    for (size_t b = 0; b < tree.branches.size(); ++b) {
      if (tree.branches[b].name == "aorta") continue;
      Tube t{{}, {}, to_hu(hu_value)};
      for (const auto& pt : tree.branches[b].points) {
        t.p_mm.push_back(pt.position_m * 1000.0);
        t.r_mm.push_back(pt.radius_m * 1000.0 + pad_mm);
      }
      tubes.push_back(std::move(t));
    }
  };
  if (spec.coronary_fat_sleeve_mm > 0) coronary_tubes(hu.fat, spec.coronary_fat_sleeve_mm);
  if (spec.coronary_lumens) coronary_tubes(spec.contrast ? spec.contrast_hu : hu.blood, 0.0);
  if (const int a = tree.find("aorta"); a >= 0 && tree.branches[a].points.size() >= 2) {
    const auto& pts = tree.branches[a].points;
    if (spec.lv_outflow) {
      // from the root's proximal end into the LV cavity; the valve is not drawn, so the outflow
      // tract, the root and the cavity are one bright region as a CTA shows them
      const double r = spec.lv_outflow_radius_mm > 0 ? spec.lv_outflow_radius_mm : 0.75 * pts.front().radius_m * 1000;
      tubes.push_back({{pts.front().position_m * 1000.0, lv_center}, {r, r}, to_hu(blood_or(spec.lv_hu))});
    }
    Tube t{{}, {}, to_hu(blood_or(spec.aorta_hu))};
    for (size_t n = 0; n < pts.size(); n += 4) {
      t.p_mm.push_back(pts[n].position_m * 1000.0);
      t.r_mm.push_back(pts[n].radius_m * 1000.0);
    }
    t.p_mm.push_back(pts.back().position_m * 1000.0);
    t.r_mm.push_back(pts.back().radius_m * 1000.0);
    // arch (a cubic Bezier over the left main bronchus) and the descending aorta beside the spine
    const Vector3d p0 = t.p_mm.back();
    const Vector3d t0 = (pts.back().position_m - pts[pts.size() - 2].position_m).normalized();
    const Vector3d d(sx + 24, sy - 26, p0.z() + 5);
    const Vector3d c1 = p0 + 45 * t0, c2 = d + Vector3d(0, 0, 45);
    const double r0 = t.r_mm.back();
    for (int n = 1; n <= 24; ++n) {
      const double u = n / 24.0, w = 1 - u;
      t.p_mm.push_back(w * w * w * p0 + 3 * w * w * u * c1 + 3 * w * u * u * c2 + u * u * u * d);
      t.r_mm.push_back(r0 + (11.5 - r0) * u);
    }
    const double z_bottom = v.origin_mm.z() - 10;
    for (double z = d.z() - 10; z > z_bottom - 10; z -= 10) {
      t.p_mm.push_back(Vector3d(d.x(), d.y(), z));
      t.r_mm.push_back(11.0);
    }
    tubes.push_back(std::move(t));
  }

  // paint in slabs of z, one per thread; within a slab: quadric spans row by row, then tubes
  const int threads =
      std::max(1, spec.threads > 0 ? spec.threads : static_cast<int>(std::thread::hardware_concurrency()));
  const Painter painter(&v);
  auto slab = [&](int64_t k_lo, int64_t k_hi) {
    for (int64_t k = k_lo; k < k_hi; ++k) {
      for (int64_t j = 0; j < v.dims[1]; ++j) {
        for (const Quadric& qq : q) painter.span(qq, j, k);
      }
    }
    for (const Tube& t : tubes) painter.tube(t, k_lo, k_hi);
  };
  std::vector<std::thread> pool;
  const int64_t per = (v.dims[2] + threads - 1) / threads;
  for (int t = 1; t < threads; ++t) {
    const int64_t lo = t * per, hi = std::min(v.dims[2], lo + per);
    if (lo < hi) pool.emplace_back(slab, lo, hi);
  }
  slab(0, std::min(v.dims[2], per));
  for (auto& th : pool) th.join();
  return v;
}

}  // namespace pcisim::anatomy
