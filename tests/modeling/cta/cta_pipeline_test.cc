// The CTA pipeline end to end on small synthetic CTAs with exact truth (anatomy/phantom/phantom_cta),
// and the hard inputs it must refuse with a message naming them.
#include "modeling/cta/cta_pipeline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "anatomy/heart/heart_mesh.h"
#include "anatomy/mesh/mesh_io.h"
#include "anatomy/phantom/phantom_cta.h"
#include "anatomy/vessel/vessel_tree_json.h"
#include "modeling/cta/modeling_error.h"
#include "tests/common/fixture_file.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

// a CTA small enough for a unit test: 0.5 mm voxels over the heart, a 60 % stenosis
anatomy::PhantomCta small_cta(uint32_t seed, bool with_coronaries = true, double stenosis = 0.6,
                              const Eigen::Matrix3d& direction = Eigen::Matrix3d::Identity(),
                              const Vector3d& spacing_mm = Vector3d(0.5, 0.5, 0.5)) {
  anatomy::PhantomCtaSpec spec;
  spec.seed = seed;
  for (int a = 0; a < 3; ++a)
    spec.dims[a] = static_cast<int64_t>(std::lround(Vector3d(130, 130, 115)[a] / spacing_mm[a]));
  spec.spacing_mm = spacing_mm;
  spec.direction = direction;
  spec.with_coronaries = with_coronaries;
  spec.stenosis_fraction = stenosis;
  return anatomy::make_phantom_cta(spec);
}

// the tree of the seed-2 model at the default options, built once per test executable build for
// the tests that read only its tree (tests/common/fixture_file.h; the JSON round trip is exact)
anatomy::VesselTree seed2_tree(const anatomy::PhantomCta& cta) {
  const std::string path = test::shared_fixture_file("cta-seed2-vessels.json", [&](const std::string& p) {
    anatomy::write_vessel_tree_json(build_cta_model(cta.ct, {cta.aortic_seed_mm}, CtaPipelineOptions{}).model.vessels,
                                    p);
  });
  return anatomy::read_vessel_tree_json(path);
}

// the distance (mm) from p_mm to the nearest centerline of the tree, the aorta left out
double distance_to_tree_mm(const anatomy::VesselTree& t, const Vector3d& p_mm);

// distance from p (m) to a branch's polyline (m)
double distance_to(const anatomy::VesselBranch& b, const Vector3d& p) {
  double best = 1e300;
  for (size_t i = 0; i + 1 < b.points.size(); ++i) {
    const Vector3d a = b.points[i].position_m, ab = b.points[i + 1].position_m - a;
    const double t = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-18), 0.0, 1.0);
    best = std::min(best, (a + t * ab - p).norm());
  }
  return best;
}

double distance_to_tree_mm(const anatomy::VesselTree& t, const Vector3d& p_mm) {
  double best = 1e300;
  for (const auto& b : t.branches) {
    if (b.name != "aorta") best = std::min(best, distance_to(b, p_mm * 1e-3) * 1e3);
  }
  return best;
}

TEST(CtaPipeline, OneAorticSeedGivesTheNamedTreeOnTheTruth) {
  const anatomy::PhantomCta cta = small_cta(2);
  const CtaModel m = build_cta_model(cta.ct, {cta.aortic_seed_mm}, CtaPipelineOptions{});
  const anatomy::VesselTree& tree = m.model.vessels;
  ASSERT_GE(tree.branches.size(), 4u);
  EXPECT_EQ(tree.branches[0].name, "aorta");
  for (const char* name : {"LM", "LAD", "LCx", "RCA"}) {
    const int mine = tree.find(name), truth = cta.truth.find(name);
    ASSERT_GE(mine, 0) << name << " not found";
    ASSERT_GE(truth, 0);
    // every model point of the vessel lies on the true vessel: within its true radius of the centerline
    double sum_mm = 0, worst_mm = 0;
    int counted = 0;
    const auto& aorta = cta.truth.branches[cta.truth.find("aorta")];
    // the LCx over its first 20 mm past the aorta only, by the median: with the tube growth a
    // marginal branch followed further than the LCx's own distal end carries the trace, and the
    // name, on into it (the labeller continues a vessel into its farthest child unless another is
    // straighter by 10 deg: coronary_labels.h); a known mislabel, docs/modeling.md
    const bool lcx = std::string(name) == "LCx";
    const int keep = lcx ? 40 : 1 << 30;
    std::vector<double> d_lcx;
    for (const auto& p : tree.branches[mine].points) {
      // points inside the aorta (the piece from its centre to the ostium) are not on a coronary,
      // and within 4 mm of its wall the model's line is the vessel's own carried back straight
      // through the ostium's funnel (off by up to ~2.5 mm there: docs/modeling.md)
      if (distance_to(aorta, p.position_m) < aorta.points.front().radius_m + 4e-3) continue;
      if (counted >= keep) break;
      ++counted;
      const double d_mm = distance_to(cta.truth.branches[truth], p.position_m) * 1e3;
      d_lcx.push_back(d_mm);
      sum_mm += d_mm;
      worst_mm = std::max(worst_mm, d_mm);
    }
    // the LM runs 2-3 mm beyond that margin in this phantom
    ASSERT_GE(counted, std::string(name) == "LM" ? 3 : 5) << name;
    std::nth_element(d_lcx.begin(), d_lcx.begin() + d_lcx.size() / 2, d_lcx.end());
    const double mean_mm = lcx ? d_lcx[d_lcx.size() / 2] : sum_mm / counted;  // the LCx's: a median
    std::printf("%s: %zu points, %.1f mm long (truth %.1f), %s distance to truth %.2f mm, worst %.2f mm\n", name,
                tree.branches[mine].points.size(), anatomy::branch_length_m(tree.branches[mine]) * 1e3,
                anatomy::branch_length_m(cta.truth.branches[truth]) * 1e3, lcx ? "median" : "mean", mean_mm, worst_mm);
    EXPECT_LT(mean_mm, 0.6) << name;  // one voxel
  }
  // each tree leaves the aortic centerline in one straight line to its ostium: the guide catheter
  // engages along the first segment, and the wire must leave it toward the ostium
  for (const char* name : {"LM", "RCA"}) {
    const auto& pts = tree.branches[tree.find(name)].points;
    const auto& aorta = tree.branches[0];
    size_t out = 1;
    while (out + 1 < pts.size() && distance_to(aorta, pts[out].position_m) < aorta.points.front().radius_m) ++out;
    const Vector3d first = pts[1].position_m - pts[0].position_m, chord = pts[out].position_m - pts[0].position_m;
    const double deg = std::acos(std::clamp(first.normalized().dot(chord.normalized()), -1.0, 1.0)) * 180 / M_PI;
    std::printf("%s: first segment %.1f deg off the line to its ostium (%.1f mm)\n", name, deg, chord.norm() * 1e3);
    EXPECT_LT(deg, 5.0) << name;
  }
  // the template heart fitted to this CT's heart: the case carries it
  EXPECT_EQ(m.model.heart_vertices_m.cols(), anatomy::template_heart_mesh().vertices_m.cols());
  // a lumen for the SDF: one closed surface stitched across the bifurcations (every tree starts
  // on the aortic centerline, so the aorta and both trees are one piece)
  EXPECT_GT(m.model.lumen.triangles.size(), 1000u);
  EXPECT_EQ(anatomy::check_closed_manifold(m.model.lumen), "");
  EXPECT_EQ(anatomy::count_components(m.model.lumen), 1);
  const auto loft =
      std::find_if(m.stages.begin(), m.stages.end(), [](const StageReport& r) { return r.name == "loft"; });
  ASSERT_NE(loft, m.stages.end());
  EXPECT_EQ(loft->figures[2].first, "components");
  EXPECT_EQ(loft->figures[2].second, 1.0);
}

// the whole pipeline on a coarse CTA (0.8 mm voxels, a quarter of the voxels of the others); the
// four named vessels lie on the truth within a voxel. Heavy under the sanitizers since it took
// 61.5 s there on a slow day (tests/heavy.txt; fewer radius iterations break its lumen check)
TEST(CtaPipeline, ACoarseCtaGivesTheNamedVesselsOnTheTruth) {
  const anatomy::PhantomCta cta = small_cta(2, true, 0.6, Eigen::Matrix3d::Identity(), Vector3d(0.8, 0.8, 0.8));
  // the 2-D level sets of the radii stop at 50 iterations (150 by default): the radii are not what
  // this test checks, and their ~1 400 sections (the tube growth's longer tree) took 9 of its 14 s,
  // near the Release suite's 20 s a test on 2 cores (scripts/test); at 20 or 35 the lumen is no
  // longer one closed surface
  CtaPipelineOptions o;
  o.radius.iterations = 50;
  const CtaModel m = build_cta_model(cta.ct, {cta.aortic_seed_mm}, o);
  const anatomy::VesselTree& tree = m.model.vessels;
  ASSERT_GE(tree.branches.size(), 4u);
  EXPECT_EQ(tree.branches[0].name, "aorta");
  const auto& aorta = cta.truth.branches[cta.truth.find("aorta")];
  for (const char* name : {"LM", "LAD", "LCx", "RCA"}) {
    const int mine = tree.find(name), truth = cta.truth.find(name);
    ASSERT_GE(mine, 0) << name << " not found";
    double sum_mm = 0;
    int counted = 0;
    // as above: the LCx's first 20 mm, by the median
    const bool lcx = std::string(name) == "LCx";
    std::vector<double> d_mm;
    for (const auto& p : tree.branches[mine].points) {
      if (distance_to(aorta, p.position_m) < aorta.points.front().radius_m + 4e-3) continue;  // as above
      if (lcx && counted >= 40) break;
      d_mm.push_back(distance_to(cta.truth.branches[truth], p.position_m) * 1e3);
      sum_mm += d_mm.back();
      ++counted;
    }
    ASSERT_GE(counted, 5) << name;
    std::nth_element(d_mm.begin(), d_mm.begin() + d_mm.size() / 2, d_mm.end());
    const double typical_mm = lcx ? d_mm[d_mm.size() / 2] : sum_mm / counted;
    std::printf("%s: %d points off the aorta, %s distance to truth %.2f mm\n", name, counted, lcx ? "median" : "mean",
                typical_mm);
    EXPECT_LT(typical_mm, 0.8) << name;  // one voxel
  }
  EXPECT_EQ(anatomy::check_closed_manifold(m.model.lumen), "");
  EXPECT_EQ(anatomy::count_components(m.model.lumen), 1);
}

// a heart fit that finds no outline leaves no fitted heart in the case (the world then dents the
// placed template under the tree) and says why; the model is built all the same
TEST(CtaPipeline, AHeartFitThatCannotBeDoneLeavesTheTemplateAsPlaced) {
  const anatomy::PhantomCta cta = small_cta(2);
  CtaPipelineOptions o;
  o.heart_fit.tissue_hu = 5000;  // nothing in the CT is heart
  const CtaModel m = build_cta_model(cta.ct, {cta.aortic_seed_mm}, o);
  EXPECT_EQ(m.model.heart_vertices_m.cols(), 0);
  const auto fit =
      std::find_if(m.stages.begin(), m.stages.end(), [](const StageReport& r) { return r.name == "heart fit"; });
  ASSERT_NE(fit, m.stages.end());
  std::string notes;
  for (const auto& n : fit->notes) notes += n + "\n";
  EXPECT_NE(notes.find("no fit kept"), std::string::npos) << notes;
  EXPECT_GE(m.model.vessels.branches.size(), 4u);
}

// the major vessels are followed along most of their length (phantom 2 at 0.5 mm, a 60 % stenosis)
TEST(CtaPipeline, EachMajorVesselIsFollowedPastHalfItsLength) {
  const anatomy::PhantomCta cta = small_cta(2);
  const anatomy::VesselTree tree = seed2_tree(cta);
  for (const char* name : {"LAD", "LCx", "RCA"}) {
    const int mine = tree.find(name), truth = cta.truth.find(name);
    ASSERT_GE(mine, 0) << name;
    EXPECT_GT(anatomy::branch_length_m(tree.branches[mine]), 0.5 * anatomy::branch_length_m(cta.truth.branches[truth]))
        << name;
  }
}

// a 95 % stenosis leaves no lumen at 0.5 mm voxels: the vessel beyond it is bridged to the tree
// (the tree continues past it) and the report says where
TEST(CtaPipeline, ATreeContinuesPastATightStenosisAndSaysWhere) {
  const anatomy::PhantomCta cta = small_cta(2, true, 0.95);
  const CtaModel m = build_cta_model(cta.ct, {cta.aortic_seed_mm}, CtaPipelineOptions{});
  const Vector3d at = cta.facts.stenosis_center_mm;
  bool said = false;
  for (const auto& st : m.stages) {
    for (const auto& note : st.notes) {
      double x0, y0, z0, x1, y1, z1, gap;
      if (std::sscanf(note.c_str(), "a gap of %lf mm bridged from (%lf, %lf, %lf) to (%lf, %lf, %lf)", &gap, &x0, &y0,
                      &z0, &x1, &y1, &z1) == 7) {
        std::printf("%s (stenosis at %.1f, %.1f, %.1f)\n", note.c_str(), at.x(), at.y(), at.z());
        if ((0.5 * (Vector3d(x0, y0, z0) + Vector3d(x1, y1, z1)) - at).norm() < 6.0) said = true;
      }
    }
  }
  EXPECT_TRUE(said) << "no note of a gap bridged within 6 mm of the stenosis on " << cta.facts.stenosis_branch;
  // the truth beyond the stenosis (from 5 to 40 mm past it) is on the model's tree
  const anatomy::VesselBranch* b = nullptr;
  for (const auto& t : cta.truth.branches) {
    if (t.name == cta.facts.stenosis_branch) b = &t;
  }
  ASSERT_NE(b, nullptr);
  int beyond = 0, found = 0;
  double s_mm = 0;
  for (size_t i = 1; i < b->points.size(); ++i) {
    s_mm += (b->points[i].position_m - b->points[i - 1].position_m).norm() * 1e3;
    const double past = s_mm - cta.facts.stenosis_arc_length_mm;
    if (past < 5.0 || past > 40.0) continue;
    ++beyond;
    const Vector3d p_mm = b->points[i].position_m * 1e3;
    if (distance_to_tree_mm(m.model.vessels, p_mm) < std::max(1.0, b->points[i].radius_m * 1e3)) ++found;
  }
  ASSERT_GT(beyond, 10);
  EXPECT_GT(found, 0.8 * beyond) << found << " of " << beyond << " truth points past the stenosis on the model";
}

// a cardiac vein runs along an artery, touching it: none of it becomes part of the tree
TEST(CtaPipeline, AVeinTouchingAnArteryIsNotMergedIntoTheTree) {
  const anatomy::PhantomCta cta = small_cta(2);
  const anatomy::VesselTree tree = seed2_tree(cta);
  const auto& vein = cta.facts.vein_points_mm;
  ASSERT_GT(vein.size(), 10u);
  // the vein's centre lies (artery radius + vein radius) from the artery's: a tree point on the
  // vein would be within its radius of it
  int on_vein = 0;
  for (size_t i = vein.size() / 5; i < vein.size() * 4 / 5; ++i) {
    if (distance_to_tree_mm(tree, vein[i]) < 0.5 * cta.facts.vein_radius_mm) ++on_vein;
  }
  EXPECT_EQ(on_vein, 0) << "of " << vein.size() * 3 / 5 << " vein points beside " << cta.facts.vein_beside;
}

// a calcified plaque touches the lumen: the model's lumen does not grow into it
TEST(CtaPipeline, ACalcifiedPlaqueIsNotTakenForLumen) {
  const anatomy::PhantomCta cta = small_cta(1);
  ASSERT_FALSE(cta.facts.plaques.empty());
  const CtaModel m = build_cta_model(cta.ct, {cta.aortic_seed_mm}, CtaPipelineOptions{});
  for (const auto& plaque : cta.facts.plaques) {
    // the lumen surface nearest the plaque's centre: centerline distance minus the model's radius
    double best = 1e300;
    for (const auto& b : m.model.vessels.branches) {
      if (b.name == "aorta") continue;
      for (const auto& p : b.points)
        best = std::min(best, (p.position_m * 1e3 - plaque.center_mm).norm() - p.radius_m * 1e3);
    }
    std::printf(
        "plaque on %s at %.1f mm: the model's lumen keeps %.2f mm from its centre (semi-axes %.1f/%.1f/%.1f mm)\n",
        plaque.branch.c_str(), plaque.arc_length_mm, best, plaque.semi_axes_mm.x(), plaque.semi_axes_mm.y(),
        plaque.semi_axes_mm.z());
    // the plaque's radial semi-axis is the least: the model's lumen stays outside half of it
    EXPECT_GT(best, 0.5 * plaque.semi_axes_mm.y()) << plaque.branch;
  }
}

// slices stored feet first: the same voxels in another order give the same model, in physical
// millimetres (every stage works through the CT's grid); and anisotropic voxels
TEST(CtaPipeline, AFlippedDirectionGivesTheSameTreeAndAnisotropicVoxelsWork) {
  const Vector3d spacing(0.45, 0.5, 0.6);
  const anatomy::PhantomCta a = small_cta(2, true, 0.6, Eigen::Matrix3d::Identity(), spacing);
  const anatomy::PhantomCta b = small_cta(2, true, 0.6, Eigen::Vector3d(1, 1, -1).asDiagonal(), spacing);
  ASSERT_LT(b.ct.direction(2, 2), 0);
  const CtaModel ma = build_cta_model(a.ct, {a.aortic_seed_mm}, CtaPipelineOptions{});
  const CtaModel mb = build_cta_model(b.ct, {b.aortic_seed_mm}, CtaPipelineOptions{});
  // the same named vessels, on each other (ties between equal-cost voxel paths break in index
  // order, so small side branches may come and go; the named vessels do not move)
  for (const char* name : {"LM", "LAD", "LCx", "RCA"}) {
    const int x = ma.model.vessels.find(name), y = mb.model.vessels.find(name);
    ASSERT_GE(x, 0) << name;
    ASSERT_GE(y, 0) << name;
    double sum = 0;
    for (const auto& p : mb.model.vessels.branches[y].points) {
      sum += distance_to(ma.model.vessels.branches[x], p.position_m) * 1e3;
    }
    const double mean_mm = sum / mb.model.vessels.branches[y].points.size();
    std::printf("%s: flipped against stored as acquired, mean distance %.3f mm\n", name, mean_mm);
    EXPECT_LT(mean_mm, 0.2) << name;
  }
  // and the anisotropic model lies on the truth where the named vessels are found
  const auto& tree = ma.model.vessels;
  for (const char* name : {"LAD", "RCA"}) {
    const int mine = tree.find(name), t = a.truth.find(name);
    ASSERT_GE(mine, 0) << name;
    double sum = 0;
    for (const auto& p : tree.branches[mine].points) sum += distance_to(a.truth.branches[t], p.position_m) * 1e3;
    EXPECT_LT(sum / tree.branches[mine].points.size(), 0.8) << name;
  }
}

TEST(CtaPipeline, ACtOverTheMemoryBoundIsRefusedWithTheNumbers) {
  const anatomy::Volume ct =
      anatomy::Volume::make({200, 200, 100}, Vector3d::Constant(0.5), Vector3d::Zero(), anatomy::VoxelType::kInt16);
  CtaPipelineOptions o;
  o.memory_limit_gb = 0.01;
  try {
    build_cta_model(ct, {Vector3d(50, 50, 25)}, o);
    FAIL() << "no error";
  } catch (const ModelingError& e) {
    EXPECT_NE(std::string(e.what()).find("200 x 200 x 100 voxels"), std::string::npos) << e.what();
    // 4 M voxels at 17 bytes a voxel (the defaults: tube growth on)
    EXPECT_NE(std::string(e.what()).find("0.07 GB"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("17 bytes a voxel"), std::string::npos) << e.what();
  }
}

TEST(CtaPipeline, ASeedOutsideTheVolumeIsNamedWithTheExtent) {
  const anatomy::PhantomCta cta = small_cta(3);
  try {
    build_cta_model(cta.ct, {cta.aortic_seed_mm + Vector3d(0, 0, 500)}, CtaPipelineOptions{});
    FAIL() << "no error";
  } catch (const ModelingError& e) {
    EXPECT_NE(std::string(e.what()).find("outside the CT"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("seed 1"), std::string::npos) << e.what();
  }
}

TEST(CtaPipeline, ASeedNotInContrastIsNamedWithItsHu) {
  const anatomy::PhantomCta cta = small_cta(3);
  // 6 mm outward from the middle of the LAD: epicardial or pericardial fat
  const auto& lad = cta.truth.branches[cta.truth.find("LAD")];
  const Vector3d mid = lad.points[lad.points.size() / 2].position_m * 1e3;
  const Vector3d off = mid + 6.0 * (mid - cta.facts.heart_center_mm).normalized();
  try {
    build_cta_model(cta.ct, {cta.aortic_seed_mm, off}, CtaPipelineOptions{});
    FAIL() << "no error";
  } catch (const ModelingError& e) {
    EXPECT_NE(std::string(e.what()).find("seed 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not in contrast"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("HU"), std::string::npos) << e.what();
  }
}

// (at 0.8 mm voxels: at 0.5 it took 65 s under ASan on a slow day, over the sanitizers' 60 s).
// The pipeline's test under the sanitizers: the fill, the clipping and the tracing up to the
// finding that no coronary leaves the aorta
TEST(CtaPipeline, ACtaWithoutCoronariesIsAnErrorNotATreeOfNoise) {
  const anatomy::PhantomCta cta =
      small_cta(4, /*with_coronaries=*/false, 0.6, Eigen::Matrix3d::Identity(), Vector3d(0.8, 0.8, 0.8));
  try {
    const CtaModel m = build_cta_model(cta.ct, {cta.aortic_seed_mm}, CtaPipelineOptions{});
    FAIL() << "a tree of " << m.model.vessels.branches.size() << " branches";
  } catch (const ModelingError& e) {
    EXPECT_NE(std::string(e.what()).find("no coronary artery"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pcisim::modeling
