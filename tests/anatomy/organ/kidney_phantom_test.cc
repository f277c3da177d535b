// The procedural kidney: a closed manifold surface whose volume is the implicit shape's, a CT that
// holds the anatomy the spec draws (cortex, pyramids and columns, sinus fat, calyces and pelvis,
// the hilum's vessels: checked at points worked out from the spec's numbers, not by the function
// that painted them), partial volume at its boundaries, and beads spread through the organ.
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

// The CT at points whose tissue the spec decides, worked out by hand from its numbers (semi-axes
// 30 x 17.5 x 55 mm, hilum depth 0.4, cortex 7 mm, sinus below s = 0.35, pyramids of 17 degrees
// at their base, calyces of 2.5 mm centred 1.25 mm inside the sinus, infundibula of 1.3 mm to the
// pelvis, an ellipsoid centred (-10, 0, 0) of 8 x 4.5 x 11 mm; the vein 4 mm round y = -4.5, the
// artery 2.5 mm round y = 3.5, medial of x = -10), each at least a millimetre from any boundary.
// Voxel centres lie on whole millimetres in x and z and half millimetres in y (the CT starts at
// -semi-axis - margin), so y = 0.5 stands for the axis (s moves < 0.2 %).
TEST(KidneyPhantom, HuAtKnownPointsIsTheDrawnTissue) {
  {
    const KidneyPhantom& p = phantom();
    Vector3d c;
    EXPECT_EQ(hu_near(p.ct, p.facts.tumour_centre_mm, &c), kKidneyTumourHu);
    for (const Vector3d& b : p.facts.fiducials_mm) EXPECT_EQ(hu_near(p.ct, b, &c), kKidneyBeadHu);
  }
  // the anatomy without the tumour and beads the seed places over it
  KidneySpec bare;
  bare.tumour_radius_mm = 0.0;
  bare.fiducial_count = 0;
  const KidneyPhantom p = make_kidney_phantom(bare);
  Vector3d c;
  const struct {
    Vector3d at_mm;
    double hu;
    const char* what;
  } known[] = {
      // the lateral axis (+x) is a pyramid's: cortex to 30 - 7 = 23 mm, the pyramid down to its
      // papilla at 0.35 x 30 = 10.5, its calyx 9.25 +- 2.5, the infundibulum along the axis to the
      // pelvis, which spans x in [-18, -2]
      {{27, 0.5, 0}, kKidneyCortexHu, "cortex on the lateral axis"},
      {{17, 0.5, 0}, kKidneyMedullaHu, "the lateral pyramid"},
      {{9, 0.5, 0}, kKidneyPelvisHu, "its calyx"},
      {{3, 0.5, 0}, kKidneyPelvisHu, "its infundibulum"},
      {{-10, 0.5, 0}, kKidneyPelvisHu, "the pelvis"},
      // medially the sinus opens to the hilum (the surface at 0.6 x 30 = 18 mm): fat beyond, the
      // vein and the artery running out through it
      {{-22, 0.5, 0}, kKidneyFatHu, "fat at the hilum"},
      {{-25, -4.5, 0}, kKidneyVeinHu, "the renal vein"},
      {{-25, 3.5, 0}, kKidneyArteryHu, "the renal artery"},
      // 45 degrees between the anterior row and the lateral border, s = 0.6 (9.8 mm deep):
      // 45 degrees from any pyramid's axis, a column of cortex between them
      {{13, -7.5, 0}, kKidneyCortexHu, "a column between pyramids"},
      // in the sinus, clear of pelvis, calyces, infundibula (4 mm from the nearest) and vessels
      {{5, 0.5, 12}, kKidneySinusFatHu, "the sinus's fat"},
      // around the organ: perirenal fat, the table behind, air beyond it
      {{0, -25.5, 0}, kKidneyFatHu, "fat in front"},
      {{0, p.spec.semi_axes_mm.y() + p.spec.table_gap_mm + 5.5, 0}, kKidneyTableHu, "the table"},
  };
  for (const auto& k : known) {
    const double hu = hu_near(p.ct, k.at_mm, &c);
    ASSERT_LT((c - k.at_mm).norm(), 0.51) << k.what;
    EXPECT_EQ(hu, k.hu) << k.what << " at " << k.at_mm.transpose();
  }
}

// the tissue map: each voxel's label is the tissue at its centre, named; where the CT's voxel is
// pure (not a boundary's) its HU is that tissue's; the organ carries the map, fitting its CT
TEST(KidneyPhantom, TheTissueMapLabelsEachVoxelsCentre) {
  const KidneyPhantom& p = phantom();
  const auto& names = kidney_tissue_names();
  ASSERT_EQ(names.size(), static_cast<size_t>(KidneyTissue::kBead) + 1);
  EXPECT_EQ(names[static_cast<int>(KidneyTissue::kCortex)], "renal cortex");
  EXPECT_EQ(names[static_cast<int>(KidneyTissue::kPelvis)], "urine");
  EXPECT_EQ(names[static_cast<int>(KidneyTissue::kSinusFat)], "renal sinus fat");
  ASSERT_EQ(p.tissue.dims, p.ct.dims);
  int64_t checked = 0, pure = 0;
  for (int64_t k = 0; k < p.ct.dims[2]; k += 3)
    for (int64_t j = 0; j < p.ct.dims[1]; j += 3)
      for (int64_t i = 0; i < p.ct.dims[0]; i += 3, ++checked) {
        const Vector3d x =
            p.ct.index_to_physical_mm(Vector3d(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)));
        const auto t = static_cast<int16_t>(kidney_tissue_at(p.spec, p.facts, x));
        ASSERT_EQ(p.tissue.hu_i16[p.tissue.linear_index(i, j, k)], t) << i << " " << j << " " << k;
        const float hu = p.ct.hu(i, j, k);
        pure += hu == kidney_tissue_hu(static_cast<KidneyTissue>(t));
      }
  // most voxels are inside one tissue (boundaries are a thin shell)
  EXPECT_GT(pure, checked * 9 / 10);
  const Organ organ = kidney_organ(p);
  ASSERT_TRUE(organ.tissue.has_value());
  EXPECT_EQ(organ.tissue->names, names);
  EXPECT_EQ(validate_tissue_map(*organ.tissue, p.ct), "");
}

// Partial volume: where a voxel's centre and its 8 corners (every other voxel) are one tissue it
// holds that tissue's HU; at the capsule on the lateral axis (x = 30 mm, the voxel centred on the surface) the HU lies
// between the fat's and the cortex's, one voxel either side pure
TEST(KidneyPhantom, BoundaryVoxelsMixTheirTissuesAndTheRestArePure) {
  const KidneyPhantom& p = phantom();
  const double h = p.ct.spacing_mm.x();
  int64_t pure = 0, wrong = 0;
  for (int64_t k = 0; k < p.ct.dims[2]; k += 2)
    for (int64_t j = 0; j < p.ct.dims[1]; j += 2)
      for (int64_t i = 0; i < p.ct.dims[0]; i += 2) {
        const Vector3d x =
            p.ct.index_to_physical_mm(Vector3d(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)));
        const KidneyTissue t = kidney_tissue_at(p.spec, p.facts, x);
        bool same = true;
        for (int corner = 0; corner < 8 && same; ++corner) {
          const Vector3d d(corner & 1 ? 0.5 : -0.5, corner & 2 ? 0.5 : -0.5, corner & 4 ? 0.5 : -0.5);
          same = kidney_tissue_at(p.spec, p.facts, x + h * d) == t;
        }
        if (!same) continue;
        ++pure;
        wrong += p.ct.hu(i, j, k) != kidney_tissue_hu(t);
      }
  // (a voxel whose corners are one tissue may still hold a pyramid's thin tip between them: 10 of
  // ~90 000 here, mixed as they should be)
  EXPECT_GT(pure, 50000);
  EXPECT_LE(wrong, pure / 2000) << "of " << pure << " voxels whose corners are one tissue";
  Vector3d c;
  const double surface = hu_near(p.ct, Vector3d(30, 0.5, 0), &c);
  EXPECT_GT(surface, kKidneyFatHu + 20.0);
  EXPECT_LT(surface, kKidneyCortexHu - 20.0);
  EXPECT_EQ(hu_near(p.ct, Vector3d(28, 0.5, 0), &c), kKidneyCortexHu);
  EXPECT_EQ(hu_near(p.ct, Vector3d(32, 0.5, 0), &c), kKidneyFatHu);
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
