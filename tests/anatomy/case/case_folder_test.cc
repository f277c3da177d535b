// A case folder written and read back is the same case; every kind of bad case is refused
// naming the file and the field; the mesh formats users bring read to the same surface.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "anatomy/case/case_folder.h"
#include "anatomy/case/case_limits.h"
#include "anatomy/heart/heart_mesh.h"
#include "anatomy/case/slicer_markups.h"
#include "anatomy/mesh/mesh_io.h"
#include "anatomy/organ/kidney_phantom.h"
#include "anatomy/phantom/phantom_case.h"
#include "anatomy/volume/volume_io.h"
#include "tests/common/file_text.h"

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;

// a small phantom case: the whole tree inside a coarse CT (fast to build)
PhantomCaseSpec small_spec() {
  PhantomCaseSpec s;
  s.seed = 3;
  s.ct_dims = {64, 64, 40};
  s.ct_spacing_mm = 4.0;
  return s;
}

const Case& small_case() {
  static const Case c = make_phantom_case(small_spec());
  return c;
}

// the soft-tissue scene's case: the kidney phantom's organ and its CT (coarse: 4 mm voxels), no vessels
const Case& kidney_case() {
  static const Case c = [] {
    KidneySpec spec;
    spec.ct_spacing_mm = 4.0;
    KidneyPhantom k = make_kidney_phantom(spec);
    Case kc;
    kc.name = "kidney phantom";
    kc.organ = kidney_organ(k);
    kc.ct = std::move(k.ct);
    return kc;
  }();
  return c;
}

class CaseFolder : public ::testing::Test {
 protected:
  virtual const Case& written() const { return small_case(); }
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pcisim-case-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->test_suite_name() +
                                        "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    write_case(written(), dir_.string());
  }
  void TearDown() override { fs::remove_all(dir_); }

  nlohmann::json case_json() const { return nlohmann::json::parse(std::ifstream(dir_ / "case.json")); }
  void set_case_json(const nlohmann::json& j) const { std::ofstream(dir_ / "case.json") << j.dump(1); }
  // the message read_case gives, or "" when it reads
  std::string refusal() const {
    try {
      read_case(dir_.string());
    } catch (const CaseError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(CaseFolder, WrittenAndReadBackIsTheSameCase) {
  const Case& a = small_case();
  const Case b = read_case(dir_.string());
  EXPECT_EQ(b.name, a.name);
  // centerlines: bit-exact doubles
  ASSERT_EQ(b.vessels.branches.size(), a.vessels.branches.size());
  for (size_t i = 0; i < a.vessels.branches.size(); ++i) {
    const auto &x = a.vessels.branches[i], &y = b.vessels.branches[i];
    EXPECT_EQ(y.name, x.name);
    EXPECT_EQ(y.parent, x.parent);
    EXPECT_EQ(y.parent_point, x.parent_point);
    ASSERT_EQ(y.points.size(), x.points.size());
    for (size_t k = 0; k < x.points.size(); ++k) {
      EXPECT_EQ(y.points[k].position_m, x.points[k].position_m) << x.name << " point " << k;
      EXPECT_EQ(y.points[k].radius_m, x.points[k].radius_m);
    }
  }
  // lumen: same vertex count, and every triangle's corners at exactly the same positions
  ASSERT_EQ(b.lumen.vertices_m.size(), a.lumen.vertices_m.size());
  ASSERT_EQ(b.lumen.triangles.size(), a.lumen.triangles.size());
  for (size_t t = 0; t < a.lumen.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(b.lumen.vertices_m[b.lumen.triangles[t][k]], a.lumen.vertices_m[a.lumen.triangles[t][k]]) << t;
  EXPECT_EQ(check_closed_manifold(b.lumen), "");
  // CT: same voxels and geometry
  ASSERT_TRUE(b.ct.has_value());
  EXPECT_EQ(b.ct->dims, a.ct->dims);
  EXPECT_EQ(b.ct->spacing_mm, a.ct->spacing_mm);
  EXPECT_EQ(b.ct->origin_mm, a.ct->origin_mm);
  EXPECT_EQ(b.ct->direction, a.ct->direction);
  EXPECT_EQ(b.ct->hu_i16, a.ct->hu_i16);
  EXPECT_EQ(b.ct_lumen_enhanced, a.ct_lumen_enhanced);
  ASSERT_EQ(b.landmarks.size(), a.landmarks.size());
  for (size_t i = 0; i < a.landmarks.size(); ++i) {
    EXPECT_EQ(b.landmarks[i].name, a.landmarks[i].name);
    EXPECT_EQ(b.landmarks[i].position_m, a.landmarks[i].position_m);
  }
}

TEST_F(CaseFolder, ACaseWithoutLesionsNamesNoLesionsFile) {
  EXPECT_FALSE(case_json().contains("lesions"));
  EXPECT_FALSE(fs::exists(dir_ / "lesions.json"));
  EXPECT_TRUE(read_case(dir_.string()).lesions.empty());
}

TEST_F(CaseFolder, SlicerCurvesAreLpsMillimetresAlongTheCenterline) {
  const auto& lad = small_case().vessels.branches.at(small_case().vessels.find("LAD"));
  const auto doc = nlohmann::json::parse(std::ifstream(dir_ / "slicer" / "LAD.mrk.json"));
  const auto& m = doc.at("markups").at(0);
  EXPECT_EQ(m.at("type"), "Curve");
  EXPECT_EQ(m.at("coordinateSystem"), "LPS");
  EXPECT_EQ(m.at("coordinateUnits"), "mm");
  ASSERT_EQ(m.at("controlPoints").size(), lad.points.size());
  for (size_t i = 0; i < lad.points.size(); i += 37) {
    const auto& p = m.at("controlPoints").at(i).at("position");
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(p.at(a).get<double>(), lad.points[i].position_m[a] * 1e3, 1e-9);
  }
  EXPECT_EQ(case_json().at("slicer_centerlines").size(), small_case().vessels.branches.size());
  // the STL header tells Slicer the space
  std::ifstream stl(dir_ / "lumen.stl", std::ios::binary);
  std::string header(80, '\0');
  stl.read(header.data(), 80);
  EXPECT_NE(header.find("SPACE=LPS"), std::string::npos) << header;
  // and a picture for people beside it (when built with libpng; without it none is named)
  if (case_overview_written()) {
    std::ifstream png(dir_ / "overview.png", std::ios::binary);
    std::string magic(8, '\0');
    png.read(magic.data(), 8);
    EXPECT_EQ(magic, "\x89PNG\r\n\x1a\n");
    EXPECT_EQ(case_json().at("overview"), "overview.png");
  } else {
    EXPECT_FALSE(fs::exists(dir_ / "overview.png"));
    EXPECT_FALSE(case_json().contains("overview"));
  }
}

// branch names become file names under slicer/ made safe: "../x" never writes outside it, and
// names that collide once made safe (or differ only in case) get files of their own
TEST_F(CaseFolder, SlicerFileNamesNeverLeaveTheSlicerFolder) {
  Case c = small_case();
  const std::vector<std::string> names = {"../x", "..", "", "a/b", "a_b", "LAD", "lad"};
  ASSERT_GE(c.vessels.branches.size(), names.size());
  c.vessels.branches.resize(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    c.vessels.branches[i].name = names[i];
    c.vessels.branches[i].parent = -1;
  }
  const fs::path sub = dir_ / "sub";
  write_case(c, sub.string());
  const std::vector<std::string> files = {"slicer/___x.mrk.json", "slicer/__.mrk.json",    "slicer/branch.mrk.json",
                                          "slicer/a_b.mrk.json",  "slicer/a_b-2.mrk.json", "slicer/LAD.mrk.json",
                                          "slicer/lad-2.mrk.json"};
  const auto doc = nlohmann::json::parse(std::ifstream(sub / "case.json"));
  EXPECT_EQ(doc.at("slicer_centerlines").get<std::vector<std::string>>(), files);
  std::set<std::string> in_slicer;
  for (const auto& f : fs::directory_iterator(sub / "slicer"))
    in_slicer.insert("slicer/" + f.path().filename().string());
  EXPECT_EQ(in_slicer, std::set<std::string>(files.begin(), files.end()));
  EXPECT_FALSE(fs::exists(sub / "x.mrk.json"));
  // each curve still carries its branch's own name for Slicer's labels
  const auto curve = nlohmann::json::parse(std::ifstream(sub / files[0]));
  EXPECT_EQ(curve.at("markups").at(0).at("labelFormat"), "../x-%d");
  EXPECT_EQ(markups_file_stem(std::string(300, 'A')), std::string(100, 'A'));
}

TEST_F(CaseFolder, MissingFileIsRefusedNamingTheField) {
  fs::remove(dir_ / "vessels.json");
  EXPECT_NE(refusal().find("case.json: vessels: file 'vessels.json' not found"), std::string::npos) << refusal();
}

TEST_F(CaseFolder, MissingCaseJsonIsRefused) {
  fs::remove(dir_ / "case.json");
  EXPECT_NE(refusal().find("case.json: missing"), std::string::npos) << refusal();
}

// a modelled patient's case places the template heart: the pose reads back as written
TEST_F(CaseFolder, TheHeartPoseReadsBackAsWritten) {
  Case c = small_case();
  c.heart.rotation = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  c.heart.scale = 1.07;
  c.heart.translation_m = Eigen::Vector3d(0.021, -0.094, -0.053);  // in the CT (or within 50 mm of it)
  write_case(c, dir_.string());
  const Case b = read_case(dir_.string());
  EXPECT_LT((b.heart.rotation - c.heart.rotation).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_DOUBLE_EQ(b.heart.scale, 1.07);
  EXPECT_LT((b.heart.translation_m - c.heart.translation_m).norm(), 1e-15);
  // the phantom's (identity) is not written, and reads back as the identity
  write_case(small_case(), dir_.string());
  EXPECT_FALSE(case_json().contains("heart"));
  EXPECT_TRUE(read_case(dir_.string()).heart.is_identity());
}

// a modelled patient's heart: the template's rest shape fitted to the CT, one vertex per template vertex
TEST_F(CaseFolder, TheFittedHeartReadsBackAsWrittenAndAWrongOneIsRefused) {
  Case c = small_case();
  c.heart.scale = 1.05;
  const Eigen::Matrix3Xd& t = template_heart_mesh().vertices_m;
  c.heart_vertices_m = t;
  c.heart_vertices_m.row(0).array() += 0.003 * (t.row(2).array() / 0.05).sin();  // up to 3 mm, every vertex
  write_case(c, dir_.string());
  EXPECT_EQ(case_json()["heart"]["rest_vertices"], "heart.node");
  const Case b = read_case(dir_.string());
  ASSERT_EQ(b.heart_vertices_m.cols(), t.cols());
  EXPECT_LT((b.heart_vertices_m - c.heart_vertices_m).cwiseAbs().maxCoeff(), 1e-15);
  // another mesh's vertices: the count is named against the template's
  Case other = c;
  other.heart_vertices_m = t.leftCols(100);
  write_case(other, dir_.string());
  EXPECT_NE(refusal().find("heart.node: nodes: 100 vertices, the template heart has " + std::to_string(t.cols())),
            std::string::npos)
      << refusal();
  // a file in metres read as millimetres: every vertex collapses to the centre, ~50 mm off
  Case metres = c;
  metres.heart_vertices_m = 1e-3 * t;
  write_case(metres, dir_.string());
  EXPECT_NE(refusal().find("mm from the template's"), std::string::npos) << refusal();
  // a broken line names the file and line
  write_case(c, dir_.string());
  {
    std::ofstream f(dir_ / "heart.node");
    f << t.cols() << " 3 0 0\n0 1 2 x\n#" << std::string(t.cols(), ' ') << "\n";  // room for the count
  }
  EXPECT_NE(refusal().find("heart.node line 2: node coordinate must be a finite number"), std::string::npos)
      << refusal();
  // a header claiming more nodes than the file can hold: refused before allocating for them
  {
    std::ofstream f(dir_ / "heart.node");
    f << "1000000000000 3 0 0\n0 1 2 3\n";
  }
  EXPECT_NE(refusal().find("node count 1000000000000 is more than the file's"), std::string::npos) << refusal();
  // a path out of the folder
  auto j = case_json();
  j["heart"]["rest_vertices"] = "../heart.node";
  set_case_json(j);
  EXPECT_NE(refusal().find("heart.rest_vertices"), std::string::npos) << refusal();
}

TEST_F(CaseFolder, AHeartPoseThatIsNotARotationIsRefused) {
  Case c = small_case();
  c.heart.scale = 1.1;
  write_case(c, dir_.string());
  auto j = case_json();
  j["heart"]["rotation"] = {{1, 0, 0}, {0, 1, 0}, {0, 0, -1}};  // a reflection
  set_case_json(j);
  EXPECT_NE(refusal().find("heart.rotation"), std::string::npos) << refusal();
  j["heart"]["rotation"] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  j["heart"]["scale"] = 5;
  set_case_json(j);
  EXPECT_NE(refusal().find("heart.scale"), std::string::npos) << refusal();
}

TEST_F(CaseFolder, WrongUnitsAreRefused) {
  auto j = case_json();
  j["units"] = "cm";
  set_case_json(j);
  EXPECT_NE(refusal().find("case.json: units: "), std::string::npos) << refusal();
  EXPECT_NE(refusal().find("mm"), std::string::npos) << refusal();
}

TEST_F(CaseFolder, WrongFrameIsRefused) {
  auto j = case_json();
  j["frame"] = "RAS";
  set_case_json(j);
  EXPECT_NE(refusal().find("case.json: frame: "), std::string::npos) << refusal();
}

// version, units and frame have no defaults: a case.json without one is refused naming it
TEST_F(CaseFolder, MissingVersionUnitsOrFrameIsRefused) {
  const auto written = case_json();
  for (const char* field : {"version", "units", "frame"}) {
    auto j = written;
    j.erase(field);
    set_case_json(j);
    EXPECT_EQ(refusal(), (dir_ / "case.json").string() + ": " + field + ": missing");
  }
}

TEST_F(CaseFolder, AFileOutsideTheFolderIsRefused) {
  auto j = case_json();
  j["lumen"] = "../lumen.stl";
  set_case_json(j);
  EXPECT_NE(refusal().find("case.json: lumen: '../lumen.stl' must be a file name inside the case folder"),
            std::string::npos)
      << refusal();
}

TEST_F(CaseFolder, AnOpenLumenIsRefused) {
  TriangleMesh m = small_case().lumen;
  m.triangles.pop_back();
  write_stl(m, (dir_ / "lumen.stl").string());
  EXPECT_NE(refusal().find("lumen.stl: mesh: open: 3 edges belong to one triangle only"), std::string::npos)
      << refusal();
}

TEST_F(CaseFolder, ANonManifoldLumenIsRefused) {
  TriangleMesh m = small_case().lumen;
  m.triangles.push_back(m.triangles.front());  // a face twice: its edges run the same way twice
  write_stl(m, (dir_ / "lumen.stl").string());
  EXPECT_NE(refusal().find("lumen.stl: mesh: non-manifold"), std::string::npos) << refusal();
}

TEST_F(CaseFolder, ACtWithoutSpacingIsRefused) {
  std::ofstream(dir_ / "ct.nrrd") << "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"
                                     "endian: little\n\n"
                                  << std::string(16, '\0');
  EXPECT_NE(refusal().find("ct.nrrd: space directions: missing"), std::string::npos) << refusal();
}

TEST_F(CaseFolder, AVesselOutsideTheCtIsRefused) {
  // the same CT shrunk to a 40 mm cube around the heart: the aorta's top leaves it
  Volume ct =
      Volume::make({10, 10, 10}, Eigen::Vector3d::Constant(4.0), Eigen::Vector3d::Constant(-18.0), VoxelType::kInt16);
  write_nrrd(ct, (dir_ / "ct.nrrd").string());
  const std::string why = refusal();
  EXPECT_NE(why.find("vessels.json: branches[0] (aorta).points["), std::string::npos) << why;
  EXPECT_NE(why.find("outside the CT ct.nrrd"), std::string::npos) << why;
}

TEST_F(CaseFolder, AnUnknownKeyIsRefused) {
  auto j = case_json();
  j["motion"] = "motion.bin";
  set_case_json(j);
  EXPECT_NE(refusal().find("case.json: motion: unknown key"), std::string::npos) << refusal();
}

TEST_F(CaseFolder, ABadVesselFileIsRefusedNamingItsField) {
  std::ofstream(dir_ / "vessels.json") << R"({"format": "pcisim-vessel-tree", "version": 1, "branches": [
    {"name": "LM", "parent": -1, "points": [{"position_m": [0, 0, 0], "radius_m": -1},
                                           {"position_m": [0, 0, 0.001], "radius_m": 0.002}]}]})";
  EXPECT_NE(refusal().find("vessels.json: branches[0].points[0].radius_m"), std::string::npos) << refusal();
}

// ---- a case with an organ (the soft-tissue scene's anatomy) ----

// the small case with two lesions on its LAD (lesions.json, issue #34)
const Case& case_with_lesions() {
  static const Case c = [] {
    Case k = small_case();
    k.lesions.push_back({"LAD", 12.5, 6.0, 1.1, 3.2, 100.0 * (1.0 - 1.1 / 3.2), 0.25, 0.4});
    k.lesions.push_back({"LAD", 30.0, 4.0, 0.8, 2.6, 100.0 * (1.0 - 0.8 / 2.6), 0.0, 0.0});
    return k;
  }();
  return c;
}

class LesionCaseFolder : public CaseFolder {
 protected:
  const Case& written() const override { return case_with_lesions(); }
  nlohmann::json lesions_json() const { return nlohmann::json::parse(std::ifstream(dir_ / "lesions.json")); }
  void set_lesions_json(const nlohmann::json& j) const { std::ofstream(dir_ / "lesions.json") << j.dump(1); }
};

TEST_F(LesionCaseFolder, LesionsAreWrittenAndReadBack) {
  EXPECT_EQ(case_json().at("lesions"), "lesions.json");
  const Case b = read_case(dir_.string());
  ASSERT_EQ(b.lesions.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const Lesion &x = case_with_lesions().lesions[i], &y = b.lesions[i];
    EXPECT_EQ(y.branch, x.branch);
    EXPECT_EQ(y.position_mm, x.position_mm);
    EXPECT_EQ(y.length_mm, x.length_mm);
    EXPECT_EQ(y.minimal_lumen_diameter_mm, x.minimal_lumen_diameter_mm);
    EXPECT_EQ(y.reference_diameter_mm, x.reference_diameter_mm);
    EXPECT_EQ(y.diameter_stenosis_pct, x.diameter_stenosis_pct);
    EXPECT_EQ(y.calcified_fraction, x.calcified_fraction);
    EXPECT_EQ(y.eccentricity, x.eccentricity);
  }
}

TEST_F(LesionCaseFolder, ALesionThatDoesNotFitTheVesselsIsRefusedNamingIt) {
  const nlohmann::json original = lesions_json();
  const auto with = [&](const char* key, const nlohmann::json& value) {
    nlohmann::json j = original;
    j["lesions"][1][key] = value;
    set_lesions_json(j);
    return refusal();
  };
  const std::string file = (dir_ / "lesions.json").string();
  EXPECT_EQ(with("branch", "XYZ"), file + ": lesions[1].branch: 'XYZ' is not a branch of the case's vessels");
  EXPECT_EQ(with("diameter_stenosis_pct", 50).rfind(file + ": lesions[1].diameter_stenosis_pct: expected 100", 0), 0u);
  nlohmann::json j = original;
  j["lesions"][1]["position_mm"] = 1e4;
  set_lesions_json(j);
  EXPECT_NE(refusal().find("lesions[1].position_mm"), std::string::npos) << refusal();
  j["lesions"][1]["position_mm"] = 30.0;
  j["lesions"][1].erase("reference_diameter_mm");
  set_lesions_json(j);
  EXPECT_EQ(refusal(), file + ": lesions[1].reference_diameter_mm: missing");
  j = original;
  j.erase("lesions");
  set_lesions_json(j);
  EXPECT_NE(refusal().find("lesions: missing"), std::string::npos) << refusal();
  j = original;
  j["format"] = "something";
  set_lesions_json(j);
  EXPECT_NE(refusal().find("format"), std::string::npos);
}

class OrganCaseFolder : public CaseFolder {
 protected:
  const Case& written() const override { return kidney_case(); }
  nlohmann::json fiducials_json() const { return nlohmann::json::parse(std::ifstream(dir_ / "fiducials.json")); }
  void set_fiducials_json(const nlohmann::json& j) const { std::ofstream(dir_ / "fiducials.json") << j.dump(1); }
  // the refusal is "<file>: <field>: <what>" with this file and field
  void expect_refused(const std::string& file, const std::string& field, const std::string& what) const {
    const std::string why = refusal();
    EXPECT_NE(why.find((dir_ / file).string() + ": " + field + ": " + what), std::string::npos) << why;
  }
};

TEST_F(OrganCaseFolder, WrittenAndReadBackIsTheSameOrgan) {
  const Case& a = kidney_case();
  const Case b = read_case(dir_.string());
  EXPECT_EQ(b.name, a.name);
  EXPECT_TRUE(b.vessels.branches.empty());
  EXPECT_FALSE(fs::exists(dir_ / "vessels.json"));
  EXPECT_FALSE(case_json().contains("vessels"));
  ASSERT_TRUE(b.organ.has_value());
  const Organ &x = *a.organ, &y = *b.organ;
  EXPECT_EQ(y.name, x.name);
  // the surface: the same vertices and triangles, each coordinate through millimetres and back
  ASSERT_EQ(y.surface.triangles, x.surface.triangles);
  ASSERT_EQ(y.surface.vertices_m.size(), x.surface.vertices_m.size());
  for (size_t v = 0; v < x.surface.vertices_m.size(); ++v)
    ASSERT_LT((y.surface.vertices_m[v] - x.surface.vertices_m[v]).norm(), 1e-16) << v;
  EXPECT_EQ(check_closed_manifold(y.surface), "");
  // beads and support: doubles through millimetres and back
  ASSERT_EQ(y.fiducials_m.size(), x.fiducials_m.size());
  ASSERT_EQ(y.fiducials_m.size(), 45u);
  for (size_t i = 0; i < x.fiducials_m.size(); ++i)
    EXPECT_LT((y.fiducials_m[i] - x.fiducials_m[i]).norm(), 1e-15) << "bead " << i;
  EXPECT_EQ(y.support_normal, x.support_normal);
  EXPECT_NEAR(y.support_offset_m, x.support_offset_m, 1e-15);
  // the CT: same voxels and geometry
  ASSERT_TRUE(b.ct.has_value());
  EXPECT_EQ(b.ct->dims, a.ct->dims);
  EXPECT_EQ(b.ct->spacing_mm, a.ct->spacing_mm);
  EXPECT_EQ(b.ct->origin_mm, a.ct->origin_mm);
  EXPECT_EQ(b.ct->direction, a.ct->direction);
  EXPECT_EQ(b.ct->hu_i16, a.ct->hu_i16);
  // case.json says where each piece is
  const auto organ = case_json().at("organ");
  EXPECT_EQ(organ.at("surface"), "organ.ply");
  EXPECT_EQ(organ.at("fiducials"), "fiducials.json");
  EXPECT_EQ(organ.at("support").at("normal"), nlohmann::json::parse("[0.0, -1.0, 0.0]"));
  EXPECT_DOUBLE_EQ(organ.at("support").at("offset_mm").get<double>(), x.support_offset_m * 1e3);
}

TEST_F(OrganCaseFolder, TheBeadsOpenInSlicerAsAPointListAndTheOverviewShowsTheOrgan) {
  const auto doc = nlohmann::json::parse(std::ifstream(dir_ / "slicer" / "fiducials.mrk.json"));
  const auto& m = doc.at("markups").at(0);
  EXPECT_EQ(m.at("type"), "Fiducial");
  EXPECT_EQ(m.at("coordinateSystem"), "LPS");
  EXPECT_EQ(m.at("coordinateUnits"), "mm");
  const auto& beads = kidney_case().organ->fiducials_m;
  ASSERT_EQ(m.at("controlPoints").size(), beads.size());
  for (size_t i = 0; i < beads.size(); ++i) {
    const auto& p = m.at("controlPoints").at(i).at("position");
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(p.at(a).get<double>(), beads[i][a] * 1e3, 1e-9);
  }
  EXPECT_EQ(case_json().at("organ").at("slicer_fiducials"), "slicer/fiducials.mrk.json");
  // the PLY's comment tells Slicer the space
  std::ifstream ply(dir_ / "organ.ply", std::ios::binary);
  std::string header(200, '\0');
  ply.read(header.data(), 200);
  EXPECT_NE(header.find("\ncomment SPACE=LPS units=mm\n"), std::string::npos) << header;
  if (case_overview_written()) {
    EXPECT_GT(fs::file_size(dir_ / "overview.png"), 1000u);
  }
}

// the organ's tissue map (issue #32): tissue.nrrd on the CT's grid, its names in case.json, a
// Slicer colour table beside it; names that do not cover a label, or labels off the CT's grid,
// are refused naming the file and what is wrong
TEST_F(OrganCaseFolder, TheTissueMapRoundTripsAndABadOneIsRefusedNamingIt) {
  const Organ& x = *kidney_case().organ;
  ASSERT_TRUE(x.tissue.has_value());
  const Case b = read_case(dir_.string());
  ASSERT_TRUE(b.organ->tissue.has_value());
  EXPECT_EQ(b.organ->tissue->names, x.tissue->names);
  EXPECT_EQ(b.organ->tissue->labels.dims, b.ct->dims);
  EXPECT_EQ(b.organ->tissue->labels.hu_i16, x.tissue->labels.hu_i16);
  const auto tissue = case_json().at("organ").at("tissue");
  EXPECT_EQ(tissue.at("labels"), "tissue.nrrd");
  EXPECT_EQ(tissue.at("names").size(), x.tissue->names.size());
  std::ifstream colors(dir_ / "slicer" / "tissue.ctbl");
  std::string line;
  int rows = 0;
  while (std::getline(colors, line)) rows += !line.empty() && line[0] != '#';
  EXPECT_EQ(rows, static_cast<int>(x.tissue->names.size()));
  // three names for eleven tissues: the first voxel of a later label is named
  auto j = case_json();
  j["organ"]["tissue"]["names"] = {"air", "perirenal fat", "acrylic"};
  set_case_json(j);
  std::string why = refusal();
  EXPECT_NE(why.find((dir_ / "tissue.nrrd").string() + ": labels: voxel ("), std::string::npos) << why;
  EXPECT_NE(why.find("not a label of the 3 names (0 to 2)"), std::string::npos) << why;
  j["organ"]["tissue"]["names"] = {"air", 3};
  set_case_json(j);
  expect_refused("case.json", "organ.tissue.names", "names[1]: expected a string");
  j["organ"]["tissue"]["names"] = {"air", "fat\nmore"};
  set_case_json(j);
  expect_refused("case.json", "organ.tissue.names", "names[1]: expected a non-empty name");
  // nor is such a map written (checked before any file is)
  Case bad = kidney_case();
  bad.organ->tissue->names[2] = std::string(65, 'x');
  const fs::path other = dir_ / "other";
  EXPECT_THROW(write_case(bad, other.string()), CaseError);
  EXPECT_FALSE(fs::exists(other / "case.json"));
  // labels on another grid (a labelmap resampled, or another CT's)
  j["organ"]["tissue"]["names"] = x.tissue->names;
  set_case_json(j);
  anatomy::Volume moved = x.tissue->labels;
  moved.origin_mm.x() += 0.5;
  write_nrrd(moved, (dir_ / "tissue.nrrd").string());
  why = refusal();
  EXPECT_NE(why.find("tissue.nrrd: labels: spacing, origin or direction differ from the CT's"), std::string::npos)
      << why;
}

// a segmented organ as users bring it: an STL (floats), read to float precision
TEST_F(OrganCaseFolder, AnStlSurfaceReadsToFloatPrecision) {
  const TriangleMesh& x = kidney_case().organ->surface;
  write_stl(x, (dir_ / "organ.stl").string());
  auto j = case_json();
  j["organ"]["surface"] = "organ.stl";
  set_case_json(j);
  const TriangleMesh y = read_case(dir_.string()).organ->surface;
  // every triangle's corners where the original's lie rounded to float mm, so within 4e-9 m
  TriangleMesh rounded = x;
  round_to_float_mm(rounded);
  ASSERT_EQ(y.triangles.size(), x.triangles.size());
  ASSERT_EQ(y.vertices_m.size(), x.vertices_m.size());
  double worst_m = 0.0;
  for (size_t t = 0; t < x.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = y.vertices_m[y.triangles[t][k]];
      ASSERT_EQ(p, rounded.vertices_m[rounded.triangles[t][k]]) << t;
      worst_m = std::max(worst_m, (p - x.vertices_m[x.triangles[t][k]]).norm());
    }
  EXPECT_LT(worst_m, 4e-9);
}

TEST_F(OrganCaseFolder, AMissingSurfaceOrBeadFileIsRefusedNamingTheField) {
  fs::remove(dir_ / "fiducials.json");
  expect_refused("case.json", "organ.fiducials", "file 'fiducials.json' not found");
  fs::remove(dir_ / "organ.ply");
  expect_refused("case.json", "organ.surface", "file 'organ.ply' not found");
}

TEST_F(OrganCaseFolder, AnOpenOrInsideOutSurfaceIsRefused) {
  TriangleMesh m = kidney_case().organ->surface;
  m.triangles.pop_back();
  write_ply_mm(m, (dir_ / "organ.ply").string());
  expect_refused("organ.ply", "mesh", "open: 3 edges belong to one triangle only");
  m = kidney_case().organ->surface;
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
  write_ply_mm(m, (dir_ / "organ.ply").string());
  expect_refused("organ.ply", "mesh", "wound inside out");
}

// inside is the surface's inside, not its bounding box's: a bead in the box's corner is refused
TEST_F(OrganCaseFolder, ABeadOutsideTheSurfaceIsRefused) {
  const auto written = fiducials_json();
  auto j = written;
  j["centres_mm"][3] = {25.0, 15.0, 50.0};  // inside the 60 x 35 x 110 mm box, outside the bean
  set_fiducials_json(j);
  expect_refused("fiducials.json", "centres_mm[3]", "at (25.0, 15.0, 50.0) mm, outside the organ's surface organ.ply");
  j["centres_mm"][3] = {0.0, 0.0, 80.0};
  set_fiducials_json(j);
  expect_refused("fiducials.json", "centres_mm[3]", "at (0.0, 0.0, 80.0) mm, outside the organ's surface");
  j = written;
  j["centres_mm"][0] = {1.0, 2.0};
  set_fiducials_json(j);
  expect_refused("fiducials.json", "centres_mm[0]", "expected [x, y, z] in millimetres");
  j = written;
  j["format"] = "slicer";
  set_fiducials_json(j);
  expect_refused("fiducials.json", "format", "expected \"pcisim-fiducials\"");
}

TEST_F(OrganCaseFolder, TheSupportNormalIsNormalisedAndAZeroOrBackwardOneIsRefused) {
  const auto written = case_json();
  auto j = written;
  j["organ"]["support"]["normal"] = {0.0, -3.0, 0.0};  // a direction: any length
  set_case_json(j);
  EXPECT_EQ(read_case(dir_.string()).organ->support_normal, Eigen::Vector3d(0, -1, 0));
  j["organ"]["support"]["normal"] = {0.0, 0.0, 0.0};
  set_case_json(j);
  expect_refused("case.json", "organ.support.normal", "expected a non-zero direction");
  j["organ"]["support"]["normal"] = {0.0, 1.0};
  set_case_json(j);
  expect_refused("case.json", "organ.support.normal", "expected [x, y, z]");
  // pointing into the organ: the organ would start inside its support
  j["organ"]["support"]["normal"] = {0.0, 1.0, 0.0};
  j["organ"]["support"]["offset_mm"] = 17.0;
  set_case_json(j);
  expect_refused("case.json", "organ.support", "the organ's centre lies");
  j = written;
  j["organ"]["support"].erase("offset_mm");
  set_case_json(j);
  expect_refused("case.json", "organ.support.offset_mm", "missing");
  j = written;
  j["organ"].erase("support");
  set_case_json(j);
  expect_refused("case.json", "organ.support", "missing");
}

TEST_F(OrganCaseFolder, AnOrganCaseWithoutItsCtOrOutsideItIsRefused) {
  auto j = case_json();
  j.erase("ct");
  set_case_json(j);
  expect_refused("case.json", "ct", "missing (an organ case needs a CT: the ultrasound images it)");
  // a CT that holds only the organ's middle: its poles (z = +-55 mm) leave it
  Volume ct =
      Volume::make({20, 20, 20}, Eigen::Vector3d::Constant(4.0), Eigen::Vector3d::Constant(-38.0), VoxelType::kInt16);
  write_nrrd(ct, (dir_ / "ct.nrrd").string());
  j["ct"] = {{"file", "ct.nrrd"}};
  set_case_json(j);
  const std::string why = refusal();
  EXPECT_NE(why.find("organ.ply: vertices["), std::string::npos) << why;
  EXPECT_NE(why.find("outside the CT ct.nrrd"), std::string::npos) << why;
}

TEST_F(OrganCaseFolder, AnUnknownOrganKeyIsRefused) {
  auto j = case_json();
  j["organ"]["stiffness"] = 3;
  set_case_json(j);
  expect_refused("case.json", "organ.stiffness", "unknown key");
}

// ---- the bounds on a case's numbers (anatomy/case/case_limits.h, docs/anatomy.md "Limits") ----

// a heart centre 1e300 m (or 5 m) away ran, and the dataset wrote samples of nothing
TEST_F(CaseFolder, ALandmarkOrTheHeartFarFromTheCtIsRefused) {
  const auto written = case_json();
  auto j = written;
  j["landmarks"][0]["position_m"] = {1e300, 0.0, 0.0};
  set_case_json(j);
  EXPECT_NE(refusal().find("case.json: landmarks[0].position_m: landmark \"heart centre\" at (1e+300, 0, 0) m is "
                           "more than 10 m from the origin"),
            std::string::npos)
      << refusal();
  j["landmarks"][0]["position_m"] = {5.0, 0.0, 0.0};
  set_case_json(j);
  EXPECT_NE(refusal().find("case.json: landmarks[0].position_m: landmark \"heart centre\" at (5000.0, 0.0, 0.0) mm "
                           "lies 4887.4 mm outside the CT ct.nrrd (at most 50 mm outside it is allowed)"),
            std::string::npos)
      << refusal();
  // near is allowed: 40 mm beyond the CT's box (which ends at x = 112.6 mm)
  j["landmarks"][0]["position_m"] = {0.1526, 0.0, 0.0};
  set_case_json(j);
  EXPECT_EQ(refusal(), "");
  // without a CT, near the centerlines' box
  j = written;
  j.erase("ct");
  j["landmarks"][0]["position_m"] = {0.0, 0.0, -1.0};
  set_case_json(j);
  EXPECT_NE(refusal().find("landmarks[0].position_m: landmark \"heart centre\" at (0.0, 0.0, -1000.0) mm lies"),
            std::string::npos)
      << refusal();
  EXPECT_NE(refusal().find("outside the centerlines' box (vessels.json; the case has no CT)"), std::string::npos)
      << refusal();
  // the heart placed half a metre away
  Case c = small_case();
  c.heart.translation_m = Eigen::Vector3d(0.5, 0.0, 0.0);
  write_case(c, dir_.string());
  EXPECT_NE(refusal().find("case.json: heart.translation_m: the heart's centre at (500.0, 0.0, 0.0) mm lies"),
            std::string::npos)
      << refusal();
}

// a support normal of [0, -1e308, 0]: its norm overflowed to inf and the normal became 0, refused
// only later by the soft-tissue effect, naming no file
TEST_F(OrganCaseFolder, AnOverflowingSupportNormalIsRefusedBeforeItIsNormalised) {
  auto j = case_json();
  j["organ"]["support"]["normal"] = {0.0, -1e308, 0.0};
  set_case_json(j);
  expect_refused("case.json", "organ.support.normal",
                 "expected a direction whose components are within +-1e+06 (any length; got [0, -1e+308, 0])");
  j["organ"]["support"]["normal"] = {1e-200, 0.0, 0.0};  // its square underflows
  set_case_json(j);
  expect_refused("case.json", "organ.support.normal", "expected a non-zero direction");
  j["organ"]["support"]["normal"] = {0.0, -1e5, 0.0};  // any length within the bound
  set_case_json(j);
  EXPECT_EQ(refusal(), "");
}

TEST_F(OrganCaseFolder, ASupportPlaneFarFromTheCtIsRefused) {
  auto j = case_json();
  j["organ"]["support"]["offset_mm"] = -5000.0;  // 5 m below the organ
  set_case_json(j);
  expect_refused("case.json", "organ.support.offset_mm", "the plane (-5000.0 mm along its normal) passes");
  EXPECT_NE(refusal().find("mm from the CT ct.nrrd (at most 50 mm outside it is allowed"), std::string::npos)
      << refusal();
}

// 90 000 beads were each tested against every triangle of the surface: 30 s before the start
TEST_F(OrganCaseFolder, TooManyBeadsOrSurfaceTrianglesAreRefusedBeforeTheWork) {
  auto f = fiducials_json();
  const auto once = f["centres_mm"];
  while (f["centres_mm"].size() <= 256)
    for (const auto& c : once) f["centres_mm"].push_back(c);
  set_fiducials_json(f);
  expect_refused("fiducials.json", "centres_mm", std::to_string(f["centres_mm"].size()) + " beads, more than 256");
  // a binary STL of one triangle over the limit (a 25 MB file of zeros): refused by its count,
  // before a corner is read
  const uint32_t n = static_cast<uint32_t>(anatomy::case_limits::kMaxOrganTriangles + 1);
  {
    std::ofstream stl(dir_ / "organ.stl", std::ios::binary);
    stl << std::string(80, ' ');
    stl.write(reinterpret_cast<const char*>(&n), 4);
    stl << std::string(size_t{50} * n, '\0');
  }
  auto j = case_json();
  j["organ"]["surface"] = "organ.stl";
  set_case_json(j);
  expect_refused(
      "organ.stl", "triangle count",
      fmt::format("{} triangles, more than {} (the limit for this mesh)", n, anatomy::case_limits::kMaxOrganTriangles));
}

// a case's meshes are read with a bound on their triangles (the lumen's 8 M, the organ's 500 k):
// every format refuses as soon as its header or its count so far passes it
TEST(MeshFiles, ATriangleLimitIsCheckedBeforeTheMeshIsParsed) {
  auto error = [](const std::string& format, const std::string& bytes) {
    try {
      parse_mesh("m" + format, format, bytes, kMillimetre, /*max_triangles=*/2);
    } catch (const MeshIoError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string stl(80, ' ');
  const uint32_t n = 3;
  stl.append(reinterpret_cast<const char*>(&n), 4);
  stl += std::string(150, '\0');
  EXPECT_EQ(error(".stl", stl), "m.stl: triangle count: 3 triangles, more than 2 (the limit for this mesh)");
  std::string ascii = "solid t\n";
  for (int t = 0; t < 3; ++t)
    ascii +=
        "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
        "endloop\nendfacet\n";
  EXPECT_EQ(error(".stl", ascii), "m.stl: facets: more than 2 triangles (the limit for this mesh)");
  const std::string ply_head =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face ";
  const std::string ply_rest = "\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  EXPECT_EQ(error(".ply", ply_head + "3" + ply_rest + "3 0 1 2\n3 0 1 3\n3 0 2 3\n"),
            "m.ply: element face: 3 faces, more than 2 (the limit for this mesh)");
  EXPECT_EQ(error(".ply", ply_head + "1" + ply_rest + "4 0 1 2 3\n3 0 2 3\n"), "");  // a quad: 2 triangles
  EXPECT_EQ(error(".ply", ply_head + "2" + ply_rest + "4 0 1 2 3\n3 0 2 3\n"),
            "m.ply: element face: more than 2 triangles (the limit for this mesh)");
  EXPECT_EQ(error(".obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3 4\nf 1 3 4\n"),
            "m.obj: line 6: more than 2 triangles (the limit for this mesh)");
  // vertices beyond what the triangles could use (3 each)
  std::string vertices;
  for (int i = 0; i < 10; ++i) vertices += "v 0 0 0\n";
  EXPECT_EQ(error(".obj", vertices), "m.obj: line 10: more than 9 vertices (the limit for this mesh)");
}

// an organ makes vessels optional only where there is one: a coronary case without its vessels
// is refused as before, and a case may hold both (each read back)
TEST_F(CaseFolder, ACoronaryCaseStillNeedsItsVessels) {
  auto j = case_json();
  j.erase("vessels");
  set_case_json(j);
  EXPECT_NE(refusal().find("case.json: vessels: '' must be a file name inside the case folder"), std::string::npos)
      << refusal();
  Case both = small_case();
  both.organ = kidney_case().organ;
  // (its tissue map lies on the kidney's CT, not this case's: refused on writing, as on reading)
  EXPECT_THROW(write_case(both, dir_.string()), CaseError);
  both.organ->tissue.reset();
  write_case(both, dir_.string());
  const Case b = read_case(dir_.string());
  EXPECT_EQ(b.vessels.branches.size(), small_case().vessels.branches.size());
  ASSERT_TRUE(b.organ.has_value());
  EXPECT_EQ(b.organ->fiducials_m.size(), 45u);
  fs::remove(dir_ / "vessels.json");
  EXPECT_NE(refusal().find("case.json: vessels: file 'vessels.json' not found"), std::string::npos) << refusal();
}

// the same surface from every format a user may bring
TEST(MeshFiles, StlPlyAndObjReadToTheSameSurface) {
  const fs::path dir = fs::temp_directory_path() / ("pcisim-mesh-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const TriangleMesh& lumen = small_case().lumen;
  // pcisim's OBJ and PLY writers write metres
  write_obj(lumen, (dir / "l.obj").string());
  write_ply(lumen, (dir / "l.ply").string());
  write_stl(lumen, (dir / "l.stl").string());
  const TriangleMesh obj = read_mesh((dir / "l.obj").string(), 1.0), ply = read_mesh((dir / "l.ply").string(), 1.0);
  const TriangleMesh stl = read_mesh((dir / "l.stl").string());
  for (const TriangleMesh* m : {&obj, &ply, &stl}) {
    ASSERT_EQ(m->triangles.size(), lumen.triangles.size());
    for (size_t t = 0; t < lumen.triangles.size(); t += 97)
      for (int k = 0; k < 3; ++k)
        EXPECT_EQ(m->vertices_m[m->triangles[t][k]], lumen.vertices_m[lumen.triangles[t][k]]) << t;
    EXPECT_EQ(check_closed_manifold(*m), "");
  }
  // ASCII STL, and a binary little-endian PLY with float vertices and a quad
  std::ofstream(dir / "a.stl") << "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                                  "endloop\nendfacet\nendsolid t\n";
  const TriangleMesh a = read_mesh((dir / "a.stl").string());
  ASSERT_EQ(a.triangles.size(), 1u);
  EXPECT_DOUBLE_EQ(a.vertices_m[1].x(), 1e-3);
  {
    std::ofstream b(dir / "b.ply", std::ios::binary);
    b << "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const float v[12] = {0, 0, 0, 2, 0, 0, 2, 2, 0, 0, 2, 0};
    b.write(reinterpret_cast<const char*>(v), sizeof v);
    const unsigned char n = 4;
    const int idx[4] = {0, 1, 2, 3};
    b.write(reinterpret_cast<const char*>(&n), 1);
    b.write(reinterpret_cast<const char*>(idx), sizeof idx);
  }
  const TriangleMesh quad = read_mesh((dir / "b.ply").string());
  ASSERT_EQ(quad.triangles.size(), 2u);
  EXPECT_DOUBLE_EQ(quad.vertices_m[2].y(), 2e-3);
  // refusals name the file
  std::ofstream(dir / "bad.obj") << "v 0 0 0\nf 1 2 3\n";
  try {
    read_mesh((dir / "bad.obj").string());
    ADD_FAILURE() << "a face on missing vertices was read";
  } catch (const MeshIoError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.obj: line 2: vertex 2 does not exist"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_mesh((dir / "l.vtk").string()), MeshIoError);
  // found by fuzzing (mesh_ply): a face index beyond int was cast (UB); a header claiming more
  // vertices than the file holds reserved gigabytes before reading them
  auto ply_error = [](const std::string& bytes) {
    try {
      parse_mesh("f.ply", ".ply", bytes);
    } catch (const MeshIoError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";
  EXPECT_EQ(ply_error(head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 4294967295\n"),
            "f.ply: face 0: vertex index 4294967295 out of range");
  EXPECT_EQ(ply_error("ply\nformat ascii 1.0\nelement vertex 268435456\nproperty float x\nend_header\n0 0 0\n"),
            "f.ply: element vertex: 268435456 rows cannot fit in the 6 bytes after the header");
  // found by fuzzing in CI (a timeout): an element of no properties and a huge count looped
  EXPECT_EQ(ply_error("ply\nformat ascii 1.0\nelement ian 8888888888888880\nend_header\n0\n"),
            "f.ply: element ian: 8888888888888880 rows of no properties");
  fs::remove_all(dir);
}

// ---- nothing in a case folder is read from outside it; a file that is no file says so (#38) ----

// the CT's detached data file outside the case (valid voxels, so only where they lie can refuse
// them): an absolute path (MetaImage), ".." (NRRD), a link out; each refused naming the header
// and the field
TEST_F(CaseFolder, ACtDataFileOutsideTheFolderIsRefused) {
  const fs::path outside = dir_.string() + "-outside";
  fs::create_directories(outside);
  write_metaimage(*small_case().ct, (outside / "ct.mhd").string());  // and outside/ct.raw
  const std::string raw = (outside / "ct.raw").string();
  auto use_ct = [&](const std::string& file, const std::string& text) {
    std::ofstream(dir_ / file, std::ios::binary) << text;
    auto j = case_json();
    j["ct"]["file"] = file;
    set_case_json(j);
  };
  const std::string mhd = test::file_text(outside / "ct.mhd");
  const std::string mhd_head = mhd.substr(0, mhd.find("ElementDataFile"));
  use_ct("ct.mhd", mhd_head + "ElementDataFile = " + raw + "\n");
  EXPECT_NE(refusal().find("ct.mhd: ElementDataFile: '" + raw + "' is an absolute path"), std::string::npos)
      << refusal();
  // the written ct.nrrd's header, its data detached
  std::string nhdr = test::file_text(dir_ / "ct.nrrd");
  nhdr = nhdr.substr(0, nhdr.find("\n\n") + 1);
  nhdr.replace(nhdr.find("encoding: "), nhdr.find('\n', nhdr.find("encoding: ")) - nhdr.find("encoding: "),
               "encoding: raw");
  const std::string up = "../" + outside.filename().string() + "/ct.raw";
  use_ct("ct.nhdr", nhdr + "data file: " + up + "\n");
  EXPECT_NE(refusal().find("ct.nhdr: data file: '" + up + "' goes up with '..'"), std::string::npos) << refusal();
  fs::create_symlink(raw, dir_ / "ct.raw");
  use_ct("ct.nhdr", nhdr + "data file: ct.raw\n");
  EXPECT_NE(refusal().find("ct.nhdr: data file: 'ct.raw' leads to '"), std::string::npos) << refusal();
  // the same bytes inside the folder are read
  fs::remove(dir_ / "ct.raw");
  fs::copy_file(raw, dir_ / "ct.raw");
  EXPECT_EQ(refusal(), "");
  fs::remove_all(outside);
}

// a member (or case.json itself) that is a symbolic link out of the folder; a link that stays
// inside is followed
TEST_F(CaseFolder, AMemberLinkedFromOutsideTheFolderIsRefused) {
  const fs::path outside = dir_.string() + "-outside";
  fs::create_directories(outside);
  fs::rename(dir_ / "lumen.stl", outside / "lumen.stl");
  fs::create_symlink(outside / "lumen.stl", dir_ / "lumen.stl");
  EXPECT_NE(refusal().find("case.json: lumen: 'lumen.stl' leads to '" + (outside / "lumen.stl").string() +
                           "' through a symbolic link, outside the folder"),
            std::string::npos)
      << refusal();
  fs::remove(dir_ / "lumen.stl");
  fs::rename(outside / "lumen.stl", dir_ / "lumen.stl");
  fs::rename(dir_ / "case.json", outside / "case.json");
  fs::create_symlink(outside / "case.json", dir_ / "case.json");
  EXPECT_NE(refusal().find("case.json: leads to '"), std::string::npos) << refusal();
  fs::remove(dir_ / "case.json");
  fs::rename(outside / "case.json", dir_ / "case.json");
  fs::create_directories(dir_ / "data");
  fs::rename(dir_ / "vessels.json", dir_ / "data" / "v.json");
  fs::create_symlink("data/v.json", dir_ / "vessels.json");
  EXPECT_EQ(refusal(), "");
  fs::remove_all(outside);
}

// a FIFO (which would block the reader), a folder, /dev/zero through a link, a device node: each
// named for what it is, never "not found"
TEST_F(CaseFolder, AFifoAFolderOrADeviceIsNotARegularFile) {
  const fs::path lumen = dir_ / "lumen.stl";
  const std::string head = "case.json: lumen: " + lumen.string() + ": not a regular file";
  fs::remove(lumen);
  ASSERT_EQ(::mkfifo(lumen.c_str(), 0600), 0);
  EXPECT_NE(refusal().find(head + " (a FIFO"), std::string::npos) << refusal();
  fs::remove(lumen);
  fs::create_directory(lumen);
  EXPECT_NE(refusal().find(head + " (a folder"), std::string::npos) << refusal();
  fs::remove(lumen);
  fs::create_symlink("/dev/zero", lumen);
  EXPECT_NE(refusal().find("case.json: lumen: 'lumen.stl' leads to '/dev/zero' (a character device)"),
            std::string::npos)
      << refusal();
  fs::remove(lumen);
  // a device node made in the folder (only where the user may make one: root)
  if (::mknod(lumen.c_str(), S_IFCHR | 0600, makedev(1, 5)) == 0) {
    const std::string why = refusal();
    EXPECT_NE(why.find("case.json: lumen: " + lumen.string() + ": "), std::string::npos) << why;
    EXPECT_EQ(why.find("not found"), std::string::npos) << why;  // a nodev mount: "cannot open"
  }
}

// a NUL in a name would cut it (the system reads "ct.nrrd"): the whole name is shown, escaped
TEST_F(CaseFolder, AControlCharacterInAFileNameIsRefusedShowingTheWholeName) {
  auto j = case_json();
  j["ct"]["file"] = std::string("ct.nrrd\0.mha", 12);
  set_case_json(j);
  EXPECT_NE(refusal().find("case.json: ct.file: 'ct.nrrd\\u0000.mha' holds a control character"), std::string::npos)
      << refusal();
  j["ct"]["file"] = "ct\n.nrrd";
  set_case_json(j);
  EXPECT_NE(refusal().find("case.json: ct.file: 'ct\\u000a.nrrd' holds a control character"), std::string::npos)
      << refusal();
}

// the seeds of the case folder's fuzz target (fuzz/targets/case_folder_fuzz.cc): a written
// phantom case and a written kidney case, shrunk so each is a few KB, that read back as cases.
// PCISIM_WRITE_CASE_FUZZ_SEEDS=DIR writes them, packed as the target reads them ("%%% NAME\n"
// then the file's bytes, entries separated by a newline), into DIR (fuzz/corpus/case_folder/)
TEST(CaseFolderFuzzSeeds, TheShrunkPhantomAndKidneyCasesReadBackAndStaySmall) {
  PhantomCaseSpec ps;
  ps.seed = 3;
  ps.ct_dims = {6, 6, 4};  // the tree inside 258 x 258 x 172 mm
  ps.ct_spacing_mm = 43.0;
  Case phantom = make_phantom_case(ps);
  // a tetrahedron for the lumen (the loft is 100s of KB), a heart pose so "heart" is written; the
  // tree (some 1300 points) thinned to every 50th point, each branch's last point and its
  // children's parent points kept (renumbered), so its topology and radii stay
  phantom.lumen.vertices_m = {{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}, {0, 0, 0.01}};
  phantom.lumen.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  phantom.heart.translation_m = {0.001, 0.0, -0.002};
  auto& branches = phantom.vessels.branches;
  std::vector<std::vector<int>> new_index(branches.size());  // -1: dropped
  for (size_t b = 0; b < branches.size(); ++b) {
    const int n = static_cast<int>(branches[b].points.size());
    std::vector<bool> keep(n);
    for (int i = 0; i < n; ++i) keep[i] = i % 50 == 0 || i + 1 == n;
    for (const auto& child : branches)
      if (child.parent == static_cast<int>(b) && child.parent_point >= 0) keep[child.parent_point] = true;
    std::vector<CenterlinePoint> kept;
    for (int i = 0; i < n; ++i) {
      new_index[b].push_back(keep[i] ? static_cast<int>(kept.size()) : -1);
      if (keep[i]) kept.push_back(branches[b].points[i]);
    }
    branches[b].points = kept;
  }
  for (auto& b : branches)
    if (b.parent >= 0 && b.parent_point >= 0) b.parent_point = new_index[b.parent][b.parent_point];
  KidneySpec ks;
  ks.surface_rings = 6;
  ks.surface_segments = 8;
  ks.fiducial_count = 3;
  ks.fiducial_min_gap_mm = 20.0;
  ks.ct_spacing_mm = 25.0;
  KidneyPhantom k = make_kidney_phantom(ks);
  Case kidney;
  kidney.name = "kidney phantom";
  kidney.organ = kidney_organ(k);
  kidney.ct = std::move(k.ct);

  const fs::path root = fs::temp_directory_path() / ("pcisim-case-seeds-" + std::to_string(::getpid()));
  const char* out = std::getenv("PCISIM_WRITE_CASE_FUZZ_SEEDS");
  using Entries = std::vector<std::pair<std::string, std::string>>;  // name (or "a -> b"), bytes
  // what read_case reads from `dir` (slicer/ and overview.png are for people), case.json first;
  // a link is packed as one ("NAME -> TARGET") and its target's folder entered
  auto entries_of = [](const fs::path& dir) {
    Entries e;
    std::vector<std::string> names;
    for (const auto& f : fs::recursive_directory_iterator(dir)) {
      const std::string rel = f.path().lexically_relative(dir).string();  // links not followed
      if (rel.rfind("slicer", 0) == 0 || rel == "overview.png" || f.is_directory() && !f.is_symlink()) continue;
      names.push_back(rel);
    }
    std::sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
      return (a != "case.json") < (b != "case.json") || ((a != "case.json") == (b != "case.json") && a < b);
    });
    for (const std::string& n : names) {
      if (fs::is_symlink(dir / n)) {
        e.emplace_back(n + " -> " + fs::read_symlink(dir / n).string(), "");
        continue;
      }
      std::ifstream in(dir / n, std::ios::binary);
      e.emplace_back(n, std::string(std::istreambuf_iterator<char>(in), {}));
    }
    return e;
  };
  // as the fuzz target reads them: "%%% NAME\n" then the bytes, a newline between entries
  auto save = [&](const std::string& seed, const Entries& entries) {
    std::string packed;
    for (const auto& [n, bytes] : entries) {
      ASSERT_EQ(bytes.find("\n%%% "), std::string::npos) << seed << ": " << n << " holds the archive's separator";
      packed += (packed.empty() ? "" : "\n") + ("%%% " + n + "\n") + bytes;
    }
    EXPECT_LT(packed.size(), 16u << 10) << seed << ": " << packed.size() << " bytes";
    if (out) std::ofstream(fs::path(out) / (seed + ".case"), std::ios::binary) << packed;
  };
  for (const auto& [name, c] : {std::pair<std::string, const Case*>{"phantom", &phantom}, {"kidney", &kidney}}) {
    const fs::path dir = root / name;
    write_case(*c, dir.string());
    ASSERT_NO_THROW(read_case(dir.string())) << name;
    save(name, entries_of(dir));
  }
  // the phantom's CT as a MetaImage with detached data, then its vessels through a link to a
  // subfolder: both read
  const fs::path dir = root / "phantom";
  write_metaimage(*phantom.ct, (dir / "ct.mhd").string());
  fs::remove(dir / "ct.nrrd");
  {
    nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "case.json"));
    j["ct"]["file"] = "ct.mhd";
    std::ofstream(dir / "case.json") << j.dump(2);
  }
  ASSERT_NO_THROW(read_case(dir.string()));
  save("phantom-detached", entries_of(dir));
  fs::create_directories(dir / "data");
  fs::rename(dir / "vessels.json", dir / "data" / "vessels.json");
  fs::create_symlink("data/vessels.json", dir / "vessels.json");
  ASSERT_NO_THROW(read_case(dir.string()));
  save("phantom-links", entries_of(dir));
  // and the hostile forms the target knows, each refused: a data file outside, a FIFO, a link out
  Entries hostile = entries_of(dir);
  for (auto& [n, bytes] : hostile) {
    if (n == "ct.mhd") bytes.replace(bytes.find("ElementDataFile = ct.raw"), 24, "ElementDataFile = ../ct.raw");
    if (n == "lumen.stl") n = "lumen.stl |fifo", bytes.clear();
    if (n == "vessels.json -> data/vessels.json") n = "vessels.json -> /dev/zero";
  }
  save("phantom-hostile", hostile);
  fs::remove_all(root);
}

}  // namespace
}  // namespace pcisim::anatomy
