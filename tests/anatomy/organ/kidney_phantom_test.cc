// The procedural kidney: a closed manifold surface whose volume is the implicit shape's, a CT that
// paints exactly the drawn tissues, and beads spread through the organ.
#include "anatomy/organ/kidney_phantom.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

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

TEST(KidneyPhantom, HuAtKnownPointsIsTheDrawnTissue) {
  const KidneyPhantom& p = phantom();
  const auto& f = p.facts;
  const Vector3d a = p.spec.semi_axes_mm;
  Vector3d c;
  EXPECT_EQ(hu_near(p.ct, f.tumour_centre_mm, &c), kKidneyTumourHu);
  for (const Vector3d& b : f.fiducials_mm) EXPECT_EQ(hu_near(p.ct, b, &c), kKidneyBeadHu);
  const struct {
    Vector3d p;
    KidneyTissue t;
  } known[] = {{{0, 0, 0.95 * a.z()}, KidneyTissue::kCortex},
               {{0.9 * a.x(), 0, 0}, KidneyTissue::kCortex},
               {{0, 0, -0.6 * a.z()}, KidneyTissue::kMedulla},
               {{0, 0, 0.2 * a.z()}, KidneyTissue::kPelvis},
               {{0, 0, a.z() + 6.0}, KidneyTissue::kFat},
               {{a.x() + 6.0, 0, 0}, KidneyTissue::kFat},
               {{0, f.table_top_y_mm + 5.0, 0}, KidneyTissue::kTable}};
  for (const auto& k : known) {
    const double hu = hu_near(p.ct, k.p, &c);
    EXPECT_EQ(kidney_tissue_at(p.spec, f, c), k.t) << c.transpose();
    EXPECT_EQ(hu, kidney_tissue_hu(k.t)) << c.transpose();
  }
  // and every voxel is its centre's classification
  int64_t wrong = 0;
  for (int64_t k = 0; k < p.ct.dims[2]; ++k)
    for (int64_t j = 0; j < p.ct.dims[1]; ++j)
      for (int64_t i = 0; i < p.ct.dims[0]; ++i) {
        const Vector3d x =
            p.ct.index_to_physical_mm(Vector3d(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)));
        wrong += p.ct.hu(i, j, k) != kidney_tissue_hu(kidney_tissue_at(p.spec, f, x));
      }
  EXPECT_EQ(wrong, 0);
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
