#include "anatomy/organ/kidney_phantom.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace pcisim::anatomy {

using Eigen::Vector3d;

double kidney_tissue_hu(KidneyTissue t) {
  switch (t) {
    case KidneyTissue::kAir:
      return kKidneyAirHu;
    case KidneyTissue::kFat:
      return kKidneyFatHu;
    case KidneyTissue::kTable:
      return kKidneyTableHu;
    case KidneyTissue::kCortex:
      return kKidneyCortexHu;
    case KidneyTissue::kMedulla:
      return kKidneyMedullaHu;
    case KidneyTissue::kPelvis:
      return kKidneyPelvisHu;
    case KidneyTissue::kSinusFat:
      return kKidneySinusFatHu;
    case KidneyTissue::kVein:
      return kKidneyVeinHu;
    case KidneyTissue::kArtery:
      return kKidneyArteryHu;
    case KidneyTissue::kTumour:
      return kKidneyTumourHu;
    case KidneyTissue::kBead:
      return kKidneyBeadHu;
  }
  return kKidneyFatHu;
}

const std::vector<std::string>& kidney_tissue_names() {
  // the table an acrylic top; the beads steel
  static const std::vector<std::string> names = {
      "air",        "perirenal fat", "acrylic", "renal cortex", "renal medulla", "urine", "renal sinus fat",
      "renal vein", "renal artery",  "tumour",  "steel"};
  return names;
}

double kidney_radius_mm(const KidneySpec& spec, const Vector3d& d) {
  const Vector3d a = spec.semi_axes_mm;
  const double ellipsoid = 1.0 / std::sqrt(d.cwiseQuotient(a).squaredNorm());
  // the hilum: a Gaussian (in the angle from the medial direction -x) pull toward the centre
  const double alpha = std::acos(std::clamp(-d.x(), -1.0, 1.0));
  const double w = spec.hilum_width_rad;
  return ellipsoid * (1.0 - spec.hilum_depth * std::exp(-alpha * alpha / (2.0 * w * w)));
}

double kidney_normalised_radius(const KidneySpec& spec, const Vector3d& p_mm) {
  const double n = p_mm.norm();
  if (n == 0.0) return 0.0;
  return n / kidney_radius_mm(spec, p_mm / n);
}

double kidney_sinus_fraction(const KidneySpec& spec, const Vector3d& p_mm) {
  const double n = p_mm.norm();
  if (n == 0.0) return spec.sinus_fraction;
  const double alpha = std::acos(std::clamp(-p_mm.x() / n, -1.0, 1.0));
  const double w = 0.6 * spec.hilum_width_rad;
  return spec.sinus_fraction + (1.0 - spec.sinus_fraction) * std::exp(-alpha * alpha / (2.0 * w * w));
}

const std::vector<Vector3d>& kidney_pyramid_axes() {
  static const std::vector<Vector3d> axes = [] {
    std::vector<Vector3d> a;
    const double deg = std::numbers::pi / 180.0;
    const auto add = [&](double latitude, double azimuth) {
      a.emplace_back(std::cos(latitude * deg) * std::cos(azimuth * deg),
                     std::cos(latitude * deg) * std::sin(azimuth * deg), std::sin(latitude * deg));
    };
    for (double latitude : {-50.0, -20.0, 20.0, 50.0})
      for (double azimuth : {-90.0, 90.0}) add(latitude, azimuth);  // the anterior and posterior rows
    for (double latitude : {-30.0, 0.0, 30.0}) add(latitude, 0.0);  // the lateral border
    add(80.0, 0.0);                                                 // the poles
    add(-80.0, 0.0);
    for (Vector3d& v : a) v.normalize();
    return a;
  }();
  return axes;
}

namespace {

// the distance from p to the segment [a, b]
double segment_distance(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const Vector3d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - a - t * ab).norm();
}

// a pyramid's calyx's centre, mm: half a calyx radius inside the sinus from the papilla (the
// pyramid's apex, on the sinus's boundary along its axis)
Vector3d calyx_centre_mm(const KidneySpec& spec, const Vector3d& axis) {
  const Vector3d papilla = spec.sinus_fraction * axis.cwiseProduct(spec.semi_axes_mm);
  return papilla - 0.5 * spec.calyx_radius_mm * papilla.normalized();
}

// inside the organ (s < 1): the sinus (urine in the pelvis, calyces and infundibula, else fat),
// the cortex within cortex_mm of the surface, and between them a pyramid where the direction lies
// within its cone (the half-angle growing linearly from 0 at the papilla to the base's at the
// cortex), else a column of cortex
KidneyTissue organ_tissue(const KidneySpec& spec, const Vector3d& p, double s) {
  const auto& axes = kidney_pyramid_axes();
  if ((p - spec.pelvis_centre_mm).cwiseQuotient(spec.pelvis_semi_axes_mm).squaredNorm() <= 1.0)
    return KidneyTissue::kPelvis;
  for (const Vector3d& a : axes) {
    const Vector3d c = calyx_centre_mm(spec, a);
    if ((p - c).norm() <= spec.calyx_radius_mm) return KidneyTissue::kPelvis;
    if (s < spec.sinus_fraction && segment_distance(p, c, spec.pelvis_centre_mm) <= spec.infundibulum_radius_mm)
      return KidneyTissue::kPelvis;
  }
  if (s < kidney_sinus_fraction(spec, p)) return KidneyTissue::kSinusFat;
  const double n = p.norm();
  const double depth = (1.0 - s) * (n > 0.0 ? n / s : 0.0);  // (1 - s) r along p's direction
  if (depth < spec.cortex_mm) return KidneyTissue::kCortex;
  const double s_base = 1.0 - spec.cortex_mm * s / n;  // s where the cortex begins along p's direction
  const double grow = std::clamp((s - spec.sinus_fraction) / (s_base - spec.sinus_fraction), 0.0, 1.0);
  const double cos_half = std::cos(grow * spec.pyramid_half_angle_deg * std::numbers::pi / 180.0);
  const Vector3d u = p.cwiseQuotient(spec.semi_axes_mm).normalized();
  for (const Vector3d& a : axes)
    if (u.dot(a) >= cos_half) return KidneyTissue::kMedulla;
  return KidneyTissue::kCortex;
}

// the renal vein and artery: cylinders along -x from the sinus's middle to beyond the organ
KidneyTissue vessel_tissue(const KidneySpec& spec, const Vector3d& p, KidneyTissue otherwise) {
  if (p.x() > spec.pelvis_centre_mm.x()) return otherwise;
  const double dv = std::hypot(p.y() + spec.vein_offset_mm, p.z());
  if (dv <= spec.vein_radius_mm) return KidneyTissue::kVein;
  const double da = std::hypot(p.y() - spec.artery_offset_mm, p.z());
  if (da <= spec.artery_radius_mm) return KidneyTissue::kArtery;
  return otherwise;
}

}  // namespace

KidneyTissue kidney_tissue_at(const KidneySpec& spec, const KidneyFacts& facts, const Vector3d& p_mm) {
  const double bead2 = spec.bead_radius_mm * spec.bead_radius_mm;
  for (const Vector3d& f : facts.fiducials_mm)
    if ((p_mm - f).squaredNorm() <= bead2) return KidneyTissue::kBead;
  if ((p_mm - facts.tumour_centre_mm).norm() <= facts.tumour_radius_mm) return KidneyTissue::kTumour;
  const double s = kidney_normalised_radius(spec, p_mm);
  if (s < 1.0) {
    const KidneyTissue t = organ_tissue(spec, p_mm, s);
    // the vessels run through the sinus's fat to the pelvis, not through the parenchyma
    return t == KidneyTissue::kSinusFat ? vessel_tissue(spec, p_mm, t) : t;
  }
  if (p_mm.y() >= facts.table_top_y_mm && p_mm.y() <= facts.table_bottom_y_mm) return KidneyTissue::kTable;
  if (p_mm.y() < facts.table_top_y_mm) {
    const KidneyTissue v = vessel_tissue(spec, p_mm, KidneyTissue::kFat);
    if (v != KidneyTissue::kFat) return v;
  }
  if (p_mm.y() > facts.table_bottom_y_mm) return KidneyTissue::kAir;
  return KidneyTissue::kFat;
}

namespace {

Vector3d direction(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

TriangleMesh make_surface(const KidneySpec& spec) {
  const int rings = spec.surface_rings, seg = spec.surface_segments;
  TriangleMesh mesh;
  auto add = [&](const Vector3d& d) {
    mesh.vertices_m.push_back(1e-3 * kidney_radius_mm(spec, d) * d);
    return static_cast<int>(mesh.vertices_m.size()) - 1;
  };
  const int north = add({0, 0, 1});
  auto ring_vertex = [&](int k, int j) { return 1 + (k - 1) * seg + (j % seg); };  // k in 1..rings-1
  for (int k = 1; k < rings; ++k)
    for (int j = 0; j < seg; ++j) add(direction(std::numbers::pi * k / rings, 2.0 * std::numbers::pi * j / seg));
  const int south = add({0, 0, -1});
  for (int j = 0; j < seg; ++j) mesh.triangles.push_back({north, ring_vertex(1, j), ring_vertex(1, j + 1)});
  for (int k = 1; k + 1 < rings; ++k)
    for (int j = 0; j < seg; ++j) {
      const int u0 = ring_vertex(k, j), u1 = ring_vertex(k, j + 1);
      const int l0 = ring_vertex(k + 1, j), l1 = ring_vertex(k + 1, j + 1);
      mesh.triangles.push_back({u0, l0, l1});
      mesh.triangles.push_back({u0, l1, u1});
    }
  for (int j = 0; j < seg; ++j)
    mesh.triangles.push_back({south, ring_vertex(rings - 1, j + 1), ring_vertex(rings - 1, j)});
  return mesh;
}

// V = integral over the sphere of r(d)^3 / 3 (midpoint rule, 600 x 1200)
double implicit_volume_mm3(const KidneySpec& spec) {
  const int nt = 600, np = 1200;
  const double dt = std::numbers::pi / nt, dp = 2.0 * std::numbers::pi / np;
  double v = 0.0;
  for (int i = 0; i < nt; ++i) {
    const double t = (i + 0.5) * dt;
    for (int j = 0; j < np; ++j) {
      const double r = kidney_radius_mm(spec, direction(t, (j + 0.5) * dp));
      v += r * r * r / 3.0 * std::sin(t) * dt * dp;
    }
  }
  return v;
}

}  // namespace

KidneyPhantom make_kidney_phantom(const KidneySpec& spec) {
  const Vector3d a = spec.semi_axes_mm;
  if (!(a.minCoeff() > 0.0) || !(spec.ct_spacing_mm > 0.0) || spec.surface_rings < 3 || spec.surface_segments < 3 ||
      !(spec.hilum_depth >= 0.0 && spec.hilum_depth < 1.0) || spec.fiducial_count < 0)
    throw std::invalid_argument("make_kidney_phantom: bad spec (sizes, spacing, hilum depth in [0,1), resolution)");
  KidneyPhantom out;
  out.spec = spec;
  KidneyFacts& facts = out.facts;
  facts.implicit_volume_mm3 = implicit_volume_mm3(spec);
  facts.table_top_y_mm = a.y() + spec.table_gap_mm;
  facts.table_bottom_y_mm = facts.table_top_y_mm + spec.table_thickness_mm;

  std::mt19937_64 rng(spec.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto random_in_box = [&] { return Vector3d(u(rng) * a.x(), u(rng) * a.y(), u(rng) * a.z()); };
  // the tumour: centre at normalised radius < 0.5, so the 15 mm sphere stays within the organ
  facts.tumour_radius_mm = spec.tumour_radius_mm;
  for (int tries = 0;; ++tries) {
    if (tries > 100000) throw std::invalid_argument("make_kidney_phantom: no place for the tumour");
    const Vector3d c = random_in_box();
    if (kidney_normalised_radius(spec, c) < 0.5) {
      facts.tumour_centre_mm = c;
      break;
    }
  }
  // beads: uniform rejection sampling inside s < 0.85, clear of the tumour and of each other
  for (int tries = 0; static_cast<int>(facts.fiducials_mm.size()) < spec.fiducial_count; ++tries) {
    if (tries > 1000000)
      throw std::invalid_argument("make_kidney_phantom: cannot place " + std::to_string(spec.fiducial_count) +
                                  " beads " + std::to_string(spec.fiducial_min_gap_mm) + " mm apart");
    const Vector3d c = random_in_box();
    if (kidney_normalised_radius(spec, c) >= 0.85) continue;
    if ((c - facts.tumour_centre_mm).norm() < facts.tumour_radius_mm + spec.bead_radius_mm + 1.0) continue;
    bool clear = true;
    for (const Vector3d& f : facts.fiducials_mm) clear = clear && (c - f).norm() >= spec.fiducial_min_gap_mm;
    if (clear) facts.fiducials_mm.push_back(c);
  }

  out.surface = make_surface(spec);

  const double h = spec.ct_spacing_mm;
  const Vector3d lo(-a.x() - spec.ct_margin_mm, -a.y() - spec.ct_margin_mm, -a.z() - spec.ct_margin_mm);
  const Vector3d hi(a.x() + spec.ct_margin_mm, facts.table_bottom_y_mm + 2.0 * h, a.z() + spec.ct_margin_mm);
  std::array<int64_t, 3> dims{};
  for (int i = 0; i < 3; ++i) dims[i] = static_cast<int64_t>(std::ceil((hi[i] - lo[i]) / h)) + 1;
  out.ct = Volume::make(dims, Vector3d::Constant(h), lo, VoxelType::kInt16);
  // each voxel centre's tissue, then partial volume where a face neighbour's differs: the HU
  // averaged over 3 x 3 x 3 points of the voxel (a boundary's voxels mixed as a scanner's are,
  // so what samples the CT between centres sees the shape, not its voxels' steps). A bead's
  // voxels stay the bead's (a fiducial is found by its bright centre)
  const auto at = [&](int64_t i, int64_t j, int64_t k) -> Vector3d {
    return lo + h * Vector3d(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
  };
  out.tissue = Volume::make(dims, Vector3d::Constant(h), lo, VoxelType::kInt16);
  std::vector<int16_t>& label = out.tissue.hu_i16;
  for (int64_t k = 0; k < dims[2]; ++k)
    for (int64_t j = 0; j < dims[1]; ++j)
      for (int64_t i = 0; i < dims[0]; ++i)
        label[out.ct.linear_index(i, j, k)] = static_cast<int16_t>(kidney_tissue_at(spec, facts, at(i, j, k)));
  for (int64_t k = 0; k < dims[2]; ++k)
    for (int64_t j = 0; j < dims[1]; ++j)
      for (int64_t i = 0; i < dims[0]; ++i) {
        const int64_t n = out.ct.linear_index(i, j, k);
        const auto tissue = static_cast<KidneyTissue>(label[n]);
        double hu = kidney_tissue_hu(tissue);
        bool mixed = false;
        for (int a = 0; a < 3 && !mixed; ++a)
          for (int step : {-1, 1}) {
            int64_t c[3] = {i, j, k};
            c[a] += step;
            if (c[a] < 0 || c[a] >= dims[a]) continue;
            mixed = mixed || label[out.ct.linear_index(c[0], c[1], c[2])] != label[n];
          }
        if (mixed && tissue != KidneyTissue::kBead) {
          double sum = 0.0;
          bool bead = false;
          for (int c = 0; c < 27 && !bead; ++c) {
            const Vector3d q = at(i, j, k) + (h / 3.0) * Vector3d(c % 3 - 1, c / 3 % 3 - 1, c / 9 - 1);
            const KidneyTissue t = kidney_tissue_at(spec, facts, q);
            bead = t == KidneyTissue::kBead;
            sum += kidney_tissue_hu(t);
          }
          if (!bead) hu = sum / 27.0;
        }
        out.ct.hu_i16[n] = static_cast<int16_t>(std::lround(hu));
      }
  return out;
}

Organ kidney_organ(const KidneyPhantom& phantom) {
  Organ organ;
  organ.name = "kidney";
  organ.surface = phantom.surface;
  for (const Eigen::Vector3d& f : phantom.facts.fiducials_mm) organ.fiducials_m.push_back(f * 1e-3);
  // the organ rests on what lies behind it: the plane touching its posterior surface (the fat
  // between it and the table taken as firm; the table itself is table_gap_mm further). Resting on
  // the table would drop it through the fat, and the CT would no longer show it where it lies
  double posterior_m = -1e30;
  for (const Eigen::Vector3d& v : organ.surface.vertices_m) posterior_m = std::max(posterior_m, v.y());
  organ.support_normal = -Eigen::Vector3d::UnitY();
  organ.support_offset_m = -posterior_m;  // -y . x >= -posterior: y <= posterior
  organ.tissue = TissueMap{phantom.tissue, kidney_tissue_names()};
  return organ;
}

}  // namespace pcisim::anatomy
