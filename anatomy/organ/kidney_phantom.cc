#include "anatomy/organ/kidney_phantom.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

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
    case KidneyTissue::kTumour:
      return kKidneyTumourHu;
    case KidneyTissue::kBead:
      return kKidneyBeadHu;
  }
  return kKidneyFatHu;
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

KidneyTissue kidney_tissue_at(const KidneySpec& spec, const KidneyFacts& facts, const Vector3d& p_mm) {
  const double bead2 = spec.bead_radius_mm * spec.bead_radius_mm;
  for (const Vector3d& f : facts.fiducials_mm)
    if ((p_mm - f).squaredNorm() <= bead2) return KidneyTissue::kBead;
  if ((p_mm - facts.tumour_centre_mm).norm() <= facts.tumour_radius_mm) return KidneyTissue::kTumour;
  const double s = kidney_normalised_radius(spec, p_mm);
  if (s < 1.0) {
    if (s < spec.pelvis_fraction) return KidneyTissue::kPelvis;
    if (s < spec.medulla_fraction) return KidneyTissue::kMedulla;
    return KidneyTissue::kCortex;
  }
  if (p_mm.y() >= facts.table_top_y_mm && p_mm.y() <= facts.table_bottom_y_mm) return KidneyTissue::kTable;
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
  for (int64_t k = 0; k < dims[2]; ++k)
    for (int64_t j = 0; j < dims[1]; ++j)
      for (int64_t i = 0; i < dims[0]; ++i) {
        const Vector3d p = lo + h * Vector3d(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
        out.ct.hu_i16[out.ct.linear_index(i, j, k)] =
            static_cast<int16_t>(kidney_tissue_hu(kidney_tissue_at(spec, facts, p)));
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
  return organ;
}

}  // namespace pcisim::anatomy
