// The procedural kidney: a closed manifold surface whose volume is the implicit shape's, a CT whose
// voxels are the layers the spec draws (judged from its semi-axes and shells, not by the function
// that painted them), and beads spread through the organ.
#include "anatomy/organ/kidney_phantom.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <array>
#include <cmath>

#include "anatomy/mesh/mesh_io.h"

namespace pcisim::anatomy {
namespace {

using Eigen::Vector3d;

const KidneyPhantom& phantom() {
  static const KidneyPhantom p = make_kidney_phantom();
  return p;
}

double mesh_volume_mm3(const TriangleMesh& mesh) {
  double v = 0.0;
  for (const auto& t : mesh.triangles)
    v += mesh.vertices_m[t[0]].dot(mesh.vertices_m[t[1]].cross(mesh.vertices_m[t[2]])) / 6.0;
  return v * 1e9;
}

double hu_near(const Volume& ct, const Vector3d& p_mm, Vector3d* centre_mm) {
  const Vector3d ijk = ct.physical_to_index(p_mm);
  const int64_t i = std::llround(ijk.x()), j = std::llround(ijk.y()), k = std::llround(ijk.z());
  *centre_mm =
      ct.index_to_physical_mm(Vector3d(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)));
  return ct.hu(i, j, k);
}

TEST(KidneyPhantom, SurfaceIsClosedManifoldWithTheImplicitVolume) {
  const KidneyPhantom& p = phantom();
  EXPECT_EQ(check_closed_manifold(p.surface), "");
  const double v = mesh_volume_mm3(p.surface);
  // a 60 x 96 latitude-longitude surface: chords cut inside the curved shape by ~0.1 %
  EXPECT_NEAR(v / p.facts.implicit_volume_mm3, 1.0, 5e-3) << v << " vs " << p.facts.implicit_volume_mm3;
  // the bean is smaller than its ellipsoid (the hilum) but not by much
  const double ellipsoid = 4.0 / 3.0 * M_PI * p.spec.semi_axes_mm.prod();
  EXPECT_LT(p.facts.implicit_volume_mm3, ellipsoid);
  EXPECT_GT(p.facts.implicit_volume_mm3, 0.85 * ellipsoid);
}

// The organ's layers from the spec alone, not from kidney_tissue_at: an ellipsoid of the spec's
// semi-axes whose radius the hilum pulls in toward -x (docs/soft-tissue.md, "The organ"), shells at
// normalised radius pelvis_fraction and medulla_fraction. The hilum only pulls the surface in: by at
// most hilum_depth (on the medial axis), and on the lateral side (x >= 0) by under 9.1e-4
// (0.4 exp(-(pi/2)^2 / (2 x 0.45^2)) = 9.04e-4). So at a voxel centre the true normalised radius
// lies in [s_e, s_e / g], s_e the bare ellipsoid's, g = 1 - 9.1e-4 laterally and 1 - hilum_depth
// medially; where that interval is inside one layer the layer is known, elsewhere the voxel is
// not judged.
enum class Expected { kUnknown, kAir, kFat, kTable, kCortex, kMedulla, kPelvis, kTumour, kBead };

Expected expected_tissue(const KidneySpec& spec, const KidneyFacts& f, const Vector3d& p) {
  const Vector3d a = spec.semi_axes_mm;
  const double s_lo = p.cwiseQuotient(a).norm(), eps = 1e-9;
  if (s_lo >= 1.0 + eps) {  // outside the ellipsoid: outside the organ, whatever the hilum does
    const double table_top = a.y() + spec.table_gap_mm, table_bottom = table_top + spec.table_thickness_mm;
    if (p.y() > table_bottom) return Expected::kAir;
    return p.y() >= table_top ? Expected::kTable : Expected::kFat;
  }
  // beads and the tumour are drawn inside the organ, over the layers
  const double bead2 = spec.bead_radius_mm * spec.bead_radius_mm;
  for (const Vector3d& b : f.fiducials_mm)
    if ((p - b).squaredNorm() <= bead2) return Expected::kBead;
  if ((p - f.tumour_centre_mm).norm() <= spec.tumour_radius_mm) return Expected::kTumour;
  const double s_hi = s_lo / (p.x() >= 0.0 ? 1.0 - 9.1e-4 : 1.0 - spec.hilum_depth);
  if (s_hi < spec.pelvis_fraction - eps) return Expected::kPelvis;
  if (s_lo > spec.pelvis_fraction + eps && s_hi < spec.medulla_fraction - eps) return Expected::kMedulla;
  if (s_lo > spec.medulla_fraction + eps && s_hi < 1.0 - eps) return Expected::kCortex;
  return Expected::kUnknown;
}

double expected_hu(Expected e) {
  switch (e) {
    case Expected::kAir:
      return -1000.0;
    case Expected::kFat:
      return -100.0;
    case Expected::kTable:
      return 200.0;
    case Expected::kCortex:
      return 150.0;
    case Expected::kMedulla:
      return 30.0;
    case Expected::kPelvis:
      return 10.0;
    case Expected::kTumour:
      return 60.0;
    case Expected::kBead:
      return 2000.0;
    case Expected::kUnknown:
      break;
  }
  return std::nan("");
}

TEST(KidneyPhantom, HuAtKnownPointsIsTheDrawnTissue) {
  const KidneyPhantom& p = phantom();
  const auto& f = p.facts;
  Vector3d c;
  EXPECT_EQ(hu_near(p.ct, f.tumour_centre_mm, &c), kKidneyTumourHu);
  for (const Vector3d& b : f.fiducials_mm) EXPECT_EQ(hu_near(p.ct, b, &c), kKidneyBeadHu);
  // the hilum: on the medial axis (-x) the capsule is pulled in to (1 - 0.4) x 30 = 18 mm, so the
  // pelvis ends at 7.2 mm, the medulla at 14.4 mm, and 21 mm out (inside the bare ellipsoid) is fat.
  // The nearest voxel centres are 0.5 mm off the axis (y on half millimetres): s moves < 0.2 %
  const struct {
    double x_mm;
    Expected e;
  } hilum[] = {
      {-4.0, Expected::kPelvis}, {-10.0, Expected::kMedulla}, {-16.0, Expected::kCortex}, {-21.0, Expected::kFat}};
  for (const auto& h : hilum) {
    const double hu = hu_near(p.ct, Vector3d(h.x_mm, 0.0, 0.0), &c);
    ASSERT_LT((c - Vector3d(h.x_mm, 0.0, 0.0)).norm(), 0.51);
    EXPECT_EQ(hu, expected_hu(h.e)) << "medial axis at " << h.x_mm << " mm";
  }
  // every voxel whose layer the spec decides, by layer: painted as that layer
  std::array<int64_t, 9> judged{}, wrong{};
  for (int64_t k = 0; k < p.ct.dims[2]; ++k)
    for (int64_t j = 0; j < p.ct.dims[1]; ++j)
      for (int64_t i = 0; i < p.ct.dims[0]; ++i) {
        const Vector3d x =
            p.ct.index_to_physical_mm(Vector3d(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)));
        const Expected e = expected_tissue(p.spec, f, x);
        if (e == Expected::kUnknown) continue;
        ++judged[static_cast<int>(e)];
        wrong[static_cast<int>(e)] += p.ct.hu(i, j, k) != expected_hu(e);
      }
  const char* names[] = {"unknown", "air", "fat", "table", "cortex", "medulla", "pelvis", "tumour", "bead"};
  std::printf("voxels judged:");
  for (int e = 1; e < 9; ++e) std::printf(" %s %ld", names[e], static_cast<long>(judged[e]));
  std::printf("\n");
  for (int e = 1; e < 9; ++e) {
    EXPECT_EQ(wrong[e], 0) << names[e] << ": " << wrong[e] << " of " << judged[e] << " voxels";
    // each layer judged on many voxels (measured: pelvis 4517, the fewest; 188 in the 45 beads)
    EXPECT_GT(judged[e], e == static_cast<int>(Expected::kBead) ? 90 : 1000) << names[e];
  }
}

TEST(KidneyPhantom, BeadsAreInsideAndSpreadAndTheSeedVaries) {
  const KidneyPhantom& p = phantom();
  ASSERT_EQ(p.facts.fiducials_mm.size(), 45u);
  for (size_t i = 0; i < p.facts.fiducials_mm.size(); ++i) {
    EXPECT_LT(kidney_normalised_radius(p.spec, p.facts.fiducials_mm[i]), 0.85);
    for (size_t j = 0; j < i; ++j)
      EXPECT_GE((p.facts.fiducials_mm[i] - p.facts.fiducials_mm[j]).norm(), p.spec.fiducial_min_gap_mm);
  }
  KidneySpec other;
  other.seed = 2;
  other.ct_spacing_mm = 4.0;
  const KidneyPhantom q = make_kidney_phantom(other);
  EXPECT_NE(q.facts.tumour_centre_mm, p.facts.tumour_centre_mm);
  EXPECT_NE(q.facts.fiducials_mm[0], p.facts.fiducials_mm[0]);
}

}  // namespace
}  // namespace pcisim::anatomy
