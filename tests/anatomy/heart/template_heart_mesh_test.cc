// The template heart: the committed TetGen mesh is sound, the coronary phantom rides its
// epicardium, the reader names file and line, and the generator reproduces the committed mesh.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>

#include "anatomy/heart/heart_frame.h"
#include "anatomy/heart/heart_mesh.h"
#include "anatomy/heart/template_heart_surface.h"
#include "anatomy/phantom/coronary_phantom.h"

namespace pcisim::anatomy {
namespace {

using Eigen::Vector3d;

// closest point on triangle abc to p (Voronoi regions of the vertices, edges and face)
Vector3d closest_on_triangle(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// signed volume enclosed by faces (positive when they face away from the enclosed region)
double enclosed_volume_m3(const HeartMesh& m, int marker) {
  double v = 0;
  for (size_t f = 0; f < m.faces.size(); ++f)
    if (m.face_markers[f] == marker) {
      const auto& t = m.faces[f];
      v += m.vertices_m.col(t[0]).dot(m.vertices_m.col(t[1]).cross(m.vertices_m.col(t[2]))) / 6.0;
    }
  return v;
}

TEST(HeartTemplateMesh, SizeAndSoundness) {
  const HeartMesh& m = template_heart_mesh();
  EXPECT_GE(m.vertices_m.cols(), 800);
  EXPECT_LE(m.vertices_m.cols(), 2000);
  double tissue_m3 = 0;
  std::set<int> used;
  for (const auto& t : m.tets) {
    const Vector3d a = m.vertices_m.col(t[0]);
    const double v =
        std::abs((m.vertices_m.col(t[1]) - a).cross(m.vertices_m.col(t[2]) - a).dot(m.vertices_m.col(t[3]) - a)) / 6;
    EXPECT_GT(v, 1e-10);  // > 0.1 mm^3: no slivers of zero volume
    tissue_m3 += v;
    used.insert(t.begin(), t.end());
  }
  EXPECT_EQ(static_cast<long>(used.size()), m.vertices_m.cols());
  // outward faces: the epicardium encloses the tissue and both cavities; each cavity's faces point
  // into it, so they enclose minus its volume; together they enclose exactly the tissue
  const double epi = enclosed_volume_m3(m, kEpicardium), lv = -enclosed_volume_m3(m, kLvEndocardium),
               rv = -enclosed_volume_m3(m, kRvEndocardium);
  EXPECT_NEAR(epi - lv - rv, tissue_m3, 1e-9);
  // adult sizes: whole heart ~0.5-0.7 l here, LV end-diastolic ~70-150 ml, RV smaller than LV
  EXPECT_GT(epi, 0.45e-3);
  EXPECT_LT(epi, 0.8e-3);
  EXPECT_GT(lv, 70e-6);
  EXPECT_LT(lv, 150e-6);
  EXPECT_GT(rv, 15e-6);
  EXPECT_LT(rv, lv);
  int counts[4] = {0, 0, 0, 0};
  for (int marker : m.face_markers) ++counts[std::clamp(marker, 0, 3)];
  EXPECT_EQ(counts[0], 0);
  EXPECT_EQ(counts[kEpicardium], 1280);
  EXPECT_EQ(counts[kLvEndocardium], 320);
  EXPECT_EQ(counts[kRvEndocardium], 320);
}

// every non-aorta centerline point of the phantom (seed 1) rides the epicardium: its distance to
// the surface minus its radius lies in [-0.5, 3] mm (the vessel touches or hovers just above it)
TEST(HeartTemplateMesh, CoronaryTreeRidesTheEpicardium) {
  const HeartMesh& m = template_heart_mesh();
  const VesselTree tree = make_coronary_phantom({1});
  int checked = 0;
  for (const auto& branch : tree.branches) {
    if (branch.name == "aorta") continue;
    double lo = 1e9, hi = -1e9;
    for (const auto& point : branch.points) {
      double d = 1e9;
      for (size_t f = 0; f < m.faces.size(); ++f) {
        if (m.face_markers[f] != kEpicardium) continue;
        const auto& t = m.faces[f];
        d = std::min(d, (point.position_m - closest_on_triangle(point.position_m, m.vertices_m.col(t[0]),
                                                                m.vertices_m.col(t[1]), m.vertices_m.col(t[2])))
                            .norm());
      }
      const double gap_mm = (d - point.radius_m) * 1e3;
      lo = std::min(lo, gap_mm);
      hi = std::max(hi, gap_mm);
      ++checked;
    }
    std::printf("%-4s gap to epicardium %+.2f .. %+.2f mm\n", branch.name.c_str(), lo, hi);
    EXPECT_GE(lo, -0.5) << branch.name;
    EXPECT_LE(hi, 3.0) << branch.name;
  }
  EXPECT_GT(checked, 1000);
}

// the atria bulge at the base, well above the 50 mm sphere, and no coronary runs over them
TEST(HeartTemplateMesh, AtriaBulgeAtTheBase) {
  const Eigen::Matrix3d to_patient = heart_to_patient();
  double highest_mm = 0;
  for (int i = 0; i < 200; ++i) {
    const double theta = 0.6 * i / 199.0, phi = 2.5 + 0.3 * std::sin(i);  // posterior base
    const Vector3d u(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    highest_mm = std::max(highest_mm, epicardial_radius_mm(u));
  }
  EXPECT_GT(highest_mm, 60.0);
  // the apex and the free walls are on the sphere
  EXPECT_DOUBLE_EQ(epicardial_radius_mm(Vector3d(0, 0, -1)), 50.0);
  EXPECT_DOUBLE_EQ(epicardial_radius_mm(Vector3d(1, 0, 0)), 50.0);
  (void)to_patient;
}

// a one-tet mesh to provoke the reader with
constexpr const char* kNode = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
constexpr const char* kEle = "1 4 0\n0 0 1 2 3\n";
constexpr const char* kFace = "4 1\n0 0 1 2 1\n1 0 1 3 1\n2 0 2 3 1\n3 1 2 3 1\n";

std::string parse_error(const std::string& node, const std::string& ele, const std::string& face) {
  try {
    parse_tetgen_mesh({node, "t.node"}, {ele, "t.ele"}, {face, "t.face"}, 1.0);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

TEST(HeartMeshReader, ParsesAndOrientsFacesOutward) {
  const HeartMesh m = parse_tetgen_mesh({kNode, "t.node"}, {kEle, "t.ele"}, {kFace, "t.face"}, 1e-3);
  ASSERT_EQ(m.vertices_m.cols(), 4);
  EXPECT_DOUBLE_EQ(m.vertices_m(0, 1), 1e-3);
  ASSERT_EQ(m.faces.size(), 4u);
  const Vector3d centre = m.vertices_m.rowwise().mean();
  for (const auto& f : m.faces) {
    const Vector3d a = m.vertices_m.col(f[0]);
    const Vector3d n = (m.vertices_m.col(f[1]) - a).cross(m.vertices_m.col(f[2]) - a);
    EXPECT_GT(n.dot(a - centre), 0.0);
  }
  // 1-based files and comments are fine too
  const HeartMesh one = parse_tetgen_mesh({"# c\n4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n", "t.node"},
                                          {"1 4 0\n1 1 2 3 4 # tet\n", "t.ele"},
                                          {"4 0\n1 1 2 3\n2 1 2 4\n3 1 3 4\n4 2 3 4\n", "t.face"}, 1.0);
  EXPECT_EQ(one.tets[0][3], 3);
  EXPECT_EQ(one.face_markers[0], 0);
}

TEST(HeartMeshReader, ErrorsNameFileAndLine) {
  EXPECT_EQ(parse_error("4 2 0 0\n", kEle, kFace), "t.node line 1: dimension must be 3");
  EXPECT_EQ(parse_error("4 3 0 0\n0 0 0 0\n1 1 x 0\n2 0 1 0\n3 0 0 1\n", kEle, kFace),
            "t.node line 3: node coordinate must be a finite number, got 'x'");
  EXPECT_EQ(parse_error("4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n", kEle, kFace),
            "t.node: expected 4 nodes, got 3 (file ends at line 4)");
  EXPECT_EQ(parse_error("4 3 0 0\n0 0 0 0\n2 1 0 0\n2 0 1 0\n3 0 0 1\n", kEle, kFace),
            "t.node line 3: node index must be 1");
  EXPECT_EQ(parse_error(kNode, "1 4 0\n0 0 1 2 9\n", kFace), "t.ele line 2: vertex index 9 is not a node");
  EXPECT_EQ(parse_error(kNode, "1 10 0\n0 0 1 2 3\n", kFace), "t.ele line 1: nodes per tet must be 4 (linear tets)");
  EXPECT_EQ(parse_error(kNode, "1 4 0\n0 0 1 2 2\n", kFace), "t.ele line 2: tet 0 is degenerate (zero volume)");
  EXPECT_EQ(parse_error(kNode, kEle, "4 1\n0 0 1 2 1\n1 0 1 3 1\n2 0 2 3\n3 1 2 3 1\n"),
            "t.face line 4: face: expected at least 5 fields, got 4");
  EXPECT_EQ(parse_error(kNode, kEle, "4 1\n0 0 1 2 1\n1 0 1 3 1\n2 0 2 3 1\n3 1 2 2 1\n"),
            "t.face line 5: face 3 bounds no tet");
  EXPECT_EQ(parse_error(kNode, kEle, ""), "t.face: no header (file ends at line 0)");
  try {
    read_tetgen_mesh("/nonexistent/heart");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/heart.node: cannot open");
  }
}

// scripts/make-heart-mesh (generator + tetgen) reproduces the committed template
TEST(HeartTemplateMesh, GeneratorReproducesCommittedMesh) {
  if (!std::filesystem::exists("/usr/bin/tetgen")) GTEST_SKIP() << "no /usr/bin/tetgen";
  const std::filesystem::path out = std::filesystem::temp_directory_path() / "pcisim_heart_mesh_test";
  std::filesystem::remove_all(out);
  const std::string cmd = std::string(PCISIM_SOURCE_DIR) + "/scripts/make-heart-mesh " + out.string() + " > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const HeartMesh fresh = read_tetgen_mesh((out / "template_heart").string());
  const HeartMesh& committed = template_heart_mesh();
  EXPECT_EQ(fresh.vertices_m.cols(), committed.vertices_m.cols());
  EXPECT_EQ(fresh.tets.size(), committed.tets.size());
  EXPECT_EQ(fresh.faces.size(), committed.faces.size());
  std::filesystem::remove_all(out);
}

}  // namespace
}  // namespace pcisim::anatomy
