// The renderer fed from the physics' tet mesh (tests may link physics; ultrasound/ never does):
// the kidney's coarse mesh (metres) as a TetSnapshot (mm), skinned by shape matching, covers the
// organ, maps a moved organ back to its rest CT, and at rest gives the undeformed image.
#include <gtest/gtest.h>

#include <cmath>

#include "anatomy/organ/kidney_phantom.h"
#include "physics/soft_tissue/tissue_model.h"
#include "ultrasound/mapping/tet_locator.h"
#include "ultrasound/render/bmode_renderer.h"

namespace pcisim::ultrasound {
namespace {

namespace st = physics::soft_tissue;
using Eigen::Vector3d;

struct KidneyMesh {
  anatomy::KidneyPhantom kidney = anatomy::make_kidney_phantom();
  st::TissueModel model;
  TetSnapshot snapshot;
  KidneyMesh() {
    std::vector<Vector3d> fiducials_m;
    for (const Vector3d& f : kidney.facts.fiducials_mm) fiducials_m.push_back(f * 1e-3);
    model = st::build_tissue_model(kidney.surface, fiducials_m);
    snapshot.rest_mm = model.tet_vertices_m * 1e3;
    snapshot.tets = model.tets;
    snapshot.current_mm = snapshot.rest_mm;
  }
  // the particles moved rigidly by t_mm, the tet vertices skinned to them
  void move_by(const Vector3d& t_mm) {
    const Eigen::Matrix3Xd x = model.rest_m.colwise() + t_mm * 1e-3;
    st::ClusterFrames frames(model);
    st::cluster_frames(model, x, &frames);
    Eigen::Matrix3Xd out(3, model.tet_skin.size());
    st::skin_points(frames, model.tet_skin, &out);
    snapshot.current_mm = out * 1e3;
  }
};

const KidneyMesh& kidney_mesh() {
  static const KidneyMesh m;
  return m;
}

TEST(UltrasoundTissueMesh, SkinnedMeshCoversTheOrganAndMapsAMovedOrganToItsRest) {
  KidneyMesh m = kidney_mesh();
  const Vector3d t(1.5, 4.0, -2.5);
  m.move_by(t);
  TetLocator locator;
  locator.build(m.snapshot);
  int tried = 0, found = 0;
  double worst = 0.0;
  for (double z = -50; z <= 50; z += 5)
    for (double y = -15; y <= 15; y += 3)
      for (double x = -25; x <= 25; x += 3) {
        const Vector3d rest(x, y, z);
        if (anatomy::kidney_normalised_radius(m.kidney.spec, rest) > 0.8) continue;
        ++tried;
        Vector3d q;
        if (!locator.to_rest(rest + t, &q)) continue;
        ++found;
        worst = std::max(worst, (q - rest).norm());
      }
  EXPECT_GT(tried, 300);
  EXPECT_EQ(found, tried);  // every particle's tet is kept, and the interior is full of particles
  EXPECT_LT(worst, 1e-6);   // rigid motion: skinning and the barycentric map undo it exactly
}

TEST(UltrasoundTissueMesh, KidneyAtRestThroughTheMeshIsTheUndeformedImage) {
  KidneyMesh m = kidney_mesh();
  m.move_by(Vector3d::Zero());
  ProbePose p;
  p.origin_mm = Vector3d(0, m.kidney.ct.origin_mm.y(), 0);
  p.beam = Vector3d::UnitY();
  p.lateral = Vector3d::UnitZ();
  BModeRenderer plain(m.kidney.ct, UsSettings{});
  const BModeImage reference = plain.render(p, 4);
  BModeRenderer mapped(m.kidney.ct, UsSettings{});
  const BModeImage& im = mapped.render(p, 4, &m.snapshot);
  int equal = 0, worst = 0;
  for (size_t i = 0; i < im.pixels.size(); ++i) {
    const int d = std::abs(im.pixels[i] - reference.pixels[i]);
    equal += d == 0;
    worst = std::max(worst, d);
  }
  EXPECT_LE(worst, 1);
  EXPECT_GE(equal, static_cast<int>(0.99 * im.pixels.size()));
}

}  // namespace
}  // namespace pcisim::ultrasound
