// Fitting the template heart under a coronary tree: trees it fits leave it untouched, trees that
// sink into it are lifted clear by a local dent that keeps every tetrahedron sound.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "physics/heart/heart_fit.h"
#include "anatomy/heart/heart_mesh.h"
#include "anatomy/heart/template_heart_surface.h"
#include "anatomy/phantom/coronary_phantom.h"

namespace pcisim::physics {
namespace {

using Eigen::Vector3d;

// radius of the mesh's epicardium along the unit direction u from the heart centre (the surface is
// star-shaped about it): Moller-Trumbore against every epicardial triangle
double mesh_radius_m(const anatomy::HeartMesh& m, const Vector3d& u) {
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_markers[f] != anatomy::kEpicardium) continue;
    const Vector3d a = m.vertices_m.col(m.faces[f][0]), b = m.vertices_m.col(m.faces[f][1]),
                   c = m.vertices_m.col(m.faces[f][2]);
    const Vector3d e1 = b - a, e2 = c - a, p = u.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-18) continue;
    const Vector3d s = -a;
    const double beta = s.dot(p) / det;
    const Vector3d q = s.cross(e1);
    const double gamma = u.dot(q) / det;
    const double t = e2.dot(q) / det;
    if (t > 0 && beta >= -1e-12 && gamma >= -1e-12 && beta + gamma <= 1 + 1e-12) return t;
  }
  return -1.0;
}

// deepest sinking of any non-aorta centerline point into the mesh (negative: sunk), metres
double worst_clearance_m(const anatomy::HeartMesh& m, const anatomy::VesselTree& tree) {
  double worst = 1e9;
  for (const auto& branch : tree.branches) {
    if (branch.name == "aorta") continue;
    for (const auto& p : branch.points) {
      const double r = p.position_m.norm();
      worst = std::min(worst, r - p.radius_m - mesh_radius_m(m, p.position_m / r));
    }
  }
  return worst;
}

double tet_volume_m3(const anatomy::HeartMesh& m, const std::array<int, 4>& t) {
  const Vector3d a = m.vertices_m.col(t[0]);
  return (m.vertices_m.col(t[1]) - a).cross(m.vertices_m.col(t[2]) - a).dot(m.vertices_m.col(t[3]) - a) / 6.0;
}

TEST(HeartFit, TreesTheTemplateFitsLeaveItUntouched) {
  for (uint32_t seed : {1u, 4u, 6u, 7u}) {
    anatomy::HeartMesh m = anatomy::template_heart_mesh();
    const HeartFitReport r = fit_heart_under_tree(anatomy::make_coronary_phantom({seed}), HeartFitParams{}, &m);
    EXPECT_EQ(r.branches_lifted, 0) << "seed " << seed;
    EXPECT_EQ(r.vertices_moved, 0) << "seed " << seed;
    EXPECT_TRUE(m.vertices_m == anatomy::template_heart_mesh().vertices_m) << "seed " << seed;
  }
}

TEST(HeartFit, SunkenBranchesAreLiftedClearByALocalDent) {
  const anatomy::HeartMesh& original = anatomy::template_heart_mesh();
  for (uint32_t seed : {2u, 3u, 5u, 8u}) {
    const anatomy::VesselTree tree = anatomy::make_coronary_phantom({seed});
    anatomy::HeartMesh m = original;
    const double before_m = worst_clearance_m(m, tree);
    const HeartFitReport r = fit_heart_under_tree(tree, HeartFitParams{}, &m);
    const double after_m = worst_clearance_m(m, tree);
    std::printf("seed %u: deepest %+.2f mm -> %+.2f mm, %d branch(es), %d vertices, dent %.2f mm\n", seed,
                before_m * 1e3, after_m * 1e3, r.branches_lifted, r.vertices_moved, r.max_dent_m * 1e3);
    EXPECT_LT(before_m, -0.75e-3) << "seed " << seed << " sinks into the template as designed";
    EXPECT_GE(after_m, -0.5e-3) << "seed " << seed << ": within the tolerance after the fit";
    EXPECT_GE(r.branches_lifted, 1);
    double deepest_designed_m = 0.0;  // against the designed surface, which the fit dents
    for (const auto& branch : tree.branches)
      if (branch.name != "aorta")
        for (const auto& p : branch.points)
          deepest_designed_m = std::min(deepest_designed_m, clearance_above_epicardium_m(p));
    EXPECT_LE(r.max_dent_m, -deepest_designed_m + 1e-12) << "no deeper than the deepest sinking";

    // local: a moved vertex lies near some sunken point; the rest of the heart is as designed
    int moved = 0;
    for (int v = 0; v < m.vertices_m.cols(); ++v) {
      if (m.vertices_m.col(v) == original.vertices_m.col(v)) continue;
      ++moved;
      EXPECT_NEAR(
          (m.vertices_m.col(v) - original.vertices_m.col(v)).normalized().dot(-original.vertices_m.col(v).normalized()),
          1.0, 1e-12)
          << "moves are radial, toward the centre";
      double nearest = 1e9;
      for (const auto& branch : tree.branches)
        if (branch.name != "aorta")
          for (const auto& p : branch.points)
            if (clearance_above_epicardium_m(p) < 0.0)
              nearest = std::min(nearest, (p.position_m - original.vertices_m.col(v)).norm());
      EXPECT_LT(nearest, 25e-3) << "vertex " << v;
    }
    EXPECT_EQ(moved, r.vertices_moved);
    EXPECT_LT(moved, original.vertices_m.cols() / 10);

    // sound: every tet keeps its orientation and at least half its volume
    for (const auto& t : m.tets) {
      const double v0 = tet_volume_m3(original, t), v1 = tet_volume_m3(m, t);
      ASSERT_GT(v1 / v0, 0.5) << "seed " << seed;
    }
  }
}

TEST(HeartFit, TighterToleranceLiftsMore) {
  const anatomy::VesselTree tree = anatomy::make_coronary_phantom({2});
  anatomy::HeartMesh loose = anatomy::template_heart_mesh(), tight = anatomy::template_heart_mesh();
  HeartFitParams p;
  const HeartFitReport a = fit_heart_under_tree(tree, p, &loose);
  p.tolerance_m = 0.1e-3;
  const HeartFitReport b = fit_heart_under_tree(tree, p, &tight);
  EXPECT_GT(b.branches_lifted, a.branches_lifted) << "seed 2's LM sinks 0.49 mm: only the tight fit lifts it";
  EXPECT_GT(worst_clearance_m(tight, tree), worst_clearance_m(loose, tree));
}

}  // namespace
}  // namespace pcisim::physics
