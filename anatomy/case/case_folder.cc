#include "anatomy/case/case_folder.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#ifdef PCISIM_ANATOMY_HAVE_PNG
#include "anatomy/case/case_overview.h"
#endif
#include "anatomy/case/case_limits.h"
#include "anatomy/case/slicer_markups.h"
#include "anatomy/heart/heart_mesh.h"
#include "anatomy/mesh/mesh_io.h"
#include "anatomy/vessel/vessel_tree_json.h"
#include "anatomy/volume/inside_folder.h"
#include "anatomy/volume/io_text.h"
#include "anatomy/volume/volume_io.h"
#include "json/json_reader.h"
#include "json/regular_file.h"

namespace pcisim::anatomy {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

[[noreturn]] void fail(const std::string& file, const std::string& field, const std::string& what) {
  throw CaseError(fmt::format("{}: {}: {}", file, field, what));
}

std::string lower_ascii(std::string s) {
  for (char& c : s)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return s;
}

// a path named by case.json: relative, no control character, and inside the folder once every
// symbolic link is followed (a case reads nothing outside its folder); `kind` is "file" or "folder"
void check_inside(const fs::path& dir, const std::string& case_json, const std::string& field, const std::string& name,
                  const char* kind) {
  const InsideFolder inside = resolve_inside_folder(dir.string(), name);
  switch (inside.escape) {
    case FolderEscape::kNone:
      return;
    case FolderEscape::kNotRelative:
      fail(case_json, field, fmt::format("'{}' must be a {} name inside the case folder", escaped_name(name), kind));
    case FolderEscape::kControlCharacter:
      fail(case_json, field,
           fmt::format("'{}' holds a control character (a {} name inside the case folder expected)", escaped_name(name),
                       kind));
    default:
      fail(case_json, field,
           fmt::format("'{}' {} (a case reads nothing outside its folder)", escaped_name(name), inside.why));
  }
}

// a file named by case.json: inside the folder (check_inside), present, and a regular file (a
// FIFO would block the reader, /dev/zero never ends, a folder is no file)
std::string member_file(const fs::path& dir, const std::string& case_json, const std::string& field,
                        const std::string& name) {
  check_inside(dir, case_json, field, name, "file");
  const fs::path full = dir / name;
  std::error_code ec;
  if (!fs::exists(fs::status(full, ec)))
    fail(case_json, field, fmt::format("file '{}' not found in {}", name, dir.string()));
  if (const std::string why = json::regular_file_problem(full.string(), "a case's " + field); !why.empty())
    fail(case_json, field, why);
  return full.string();
}

// every centerline point inside the CT's extent (half a voxel beyond the outer voxel centres)
void check_vessels_inside(const VesselTree& tree, const Volume& ct, const std::string& vessels_file,
                          const std::string& ct_file) {
  for (size_t b = 0; b < tree.branches.size(); ++b) {
    const auto& branch = tree.branches[b];
    for (size_t i = 0; i < branch.points.size(); ++i) {
      const Eigen::Vector3d p_mm = branch.points[i].position_m * 1e3;
      const Eigen::Vector3d ijk = ct.physical_to_index(p_mm);
      bool inside = true;
      // (a thousandth of a voxel of slack: positions from DICOM text round)
      for (int a = 0; a < 3; ++a) inside = inside && ijk[a] >= -0.501 && ijk[a] <= ct.dims[a] - 0.499;
      if (!inside)
        fail(vessels_file, fmt::format("branches[{}] ({}).points[{}]", b, branch.name, i),
             fmt::format("at ({:.1f}, {:.1f}, {:.1f}) mm, outside the CT {} (voxel index {:.1f}, {:.1f}, {:.1f} of "
                         "{}x{}x{})",
                         p_mm.x(), p_mm.y(), p_mm.z(), fs::path(ct_file).filename().string(), ijk.x(), ijk.y(), ijk.z(),
                         ct.dims[0], ct.dims[1], ct.dims[2]));
    }
  }
}

// every vertex of the organ's surface inside the CT's extent: the ultrasound images the organ
// from the CT, so a surface in other units or another frame is refused here
void check_organ_inside(const TriangleMesh& surface, const Volume& ct, const std::string& surface_file,
                        const std::string& ct_file) {
  for (size_t v = 0; v < surface.vertices_m.size(); ++v) {
    const Eigen::Vector3d p_mm = surface.vertices_m[v] * 1e3;
    const Eigen::Vector3d ijk = ct.physical_to_index(p_mm);
    bool inside = true;
    for (int a = 0; a < 3; ++a) inside = inside && ijk[a] >= -0.501 && ijk[a] <= ct.dims[a] - 0.499;
    if (!inside)
      fail(surface_file, fmt::format("vertices[{}]", v),
           fmt::format("at ({:.1f}, {:.1f}, {:.1f}) mm, outside the CT {} (an organ case's CT must hold its organ)",
                       p_mm.x(), p_mm.y(), p_mm.z(), fs::path(ct_file).filename().string()));
  }
}

// ---- where a case's points may lie (docs/anatomy.md, "Limits"; bounds in case_limits.h) ----

using namespace case_limits;

// every vertex of a case's mesh within kMaxCoordinateM of the origin: products of coordinates
// (volumes, winding numbers) then stay finite
void check_mesh_coordinates(const TriangleMesh& mesh, const std::string& file) {
  for (size_t v = 0; v < mesh.vertices_m.size(); ++v)
    if (!(mesh.vertices_m[v].cwiseAbs().maxCoeff() <= kMaxCoordinateM)) {
      const Eigen::Vector3d& p = mesh.vertices_m[v];
      fail(file, fmt::format("vertices[{}]", v),
           fmt::format("at ({:.6g}, {:.6g}, {:.6g}) m, more than {:.0f} m from the origin (a patient is smaller)",
                       p.x(), p.y(), p.z(), kMaxCoordinateM));
    }
}

// the box a case's landmarks, heart and support must lie in or near: the CT's (half a voxel
// beyond its outer voxel centres), or without a CT the centerlines'
struct NearBox {
  const Volume* ct = nullptr;
  Eigen::Vector3d lo_mm = Eigen::Vector3d::Zero(), hi_mm = Eigen::Vector3d::Zero();  // without a CT
  std::string name;                                                                  // "the CT ct.nrrd", for messages
};

NearBox near_box(const Case& c, const std::string& ct_file, const std::string& vessels_file) {
  NearBox box;
  if (c.ct) {
    box.ct = &*c.ct;
    box.name = "the CT " + fs::path(ct_file).filename().string();
    return box;
  }
  box.lo_mm = Eigen::Vector3d::Constant(INFINITY);
  box.hi_mm = -box.lo_mm;
  for (const auto& b : c.vessels.branches)
    for (const auto& p : b.points) {
      box.lo_mm = box.lo_mm.cwiseMin(p.position_m * 1e3);
      box.hi_mm = box.hi_mm.cwiseMax(p.position_m * 1e3);
    }
  box.name = "the centerlines' box (" + fs::path(vessels_file).filename().string() + "; the case has no CT)";
  return box;
}

// the box's corners, mm
std::array<Eigen::Vector3d, 8> box_corners_mm(const NearBox& box) {
  std::array<Eigen::Vector3d, 8> corners;
  for (int k = 0; k < 8; ++k) {
    Eigen::Vector3d x;
    for (int a = 0; a < 3; ++a) {
      const bool high = (k >> a) & 1;
      x[a] = box.ct ? (high ? box.ct->dims[a] - 0.5 : -0.5) : (high ? box.hi_mm[a] : box.lo_mm[a]);
    }
    corners[k] = box.ct ? box.ct->index_to_physical_mm(x) : x;
  }
  return corners;
}

// how far p lies outside the box, mm (0 inside)
double mm_outside(const NearBox& box, const Eigen::Vector3d& p_mm) {
  Eigen::Vector3d out_mm;
  if (box.ct) {
    const Eigen::Vector3d ijk = box.ct->physical_to_index(p_mm);
    for (int a = 0; a < 3; ++a)
      out_mm[a] = std::max({-0.5 - ijk[a], ijk[a] - (box.ct->dims[a] - 0.5), 0.0}) * box.ct->spacing_mm[a];
  } else {
    for (int a = 0; a < 3; ++a) out_mm[a] = std::max({box.lo_mm[a] - p_mm[a], p_mm[a] - box.hi_mm[a], 0.0});
  }
  return out_mm.norm();
}

// a point of case.json (a landmark, the heart's place) inside the box or within kNearCtMm of it
void check_near(const NearBox& box, const Eigen::Vector3d& p_m, const std::string& file, const std::string& field,
                const std::string& what) {
  if (!(p_m.cwiseAbs().maxCoeff() <= kMaxCoordinateM))
    fail(file, field,
         fmt::format("{} at ({:.6g}, {:.6g}, {:.6g}) m is more than {:.0f} m from the origin (it must lie inside "
                     "{} or within {:.0f} mm of it)",
                     what, p_m.x(), p_m.y(), p_m.z(), kMaxCoordinateM, box.name, kNearCtMm));
  const Eigen::Vector3d p_mm = p_m * 1e3;
  const double out_mm = mm_outside(box, p_mm);
  if (!(out_mm <= kNearCtMm))
    fail(file, field,
         fmt::format("{} at ({:.1f}, {:.1f}, {:.1f}) mm lies {:.1f} mm outside {} (at most {:.0f} mm outside it "
                     "is allowed)",
                     what, p_mm.x(), p_mm.y(), p_mm.z(), out_mm, box.name, kNearCtMm));
}

// the support plane (unit normal, offset) passes through the box or within kNearCtMm of it
void check_plane_near(const NearBox& box, const Eigen::Vector3d& normal, double offset_m, const std::string& file,
                      const std::string& field) {
  double lo_mm = INFINITY, hi_mm = -INFINITY;
  for (const Eigen::Vector3d& x : box_corners_mm(box)) {
    lo_mm = std::min(lo_mm, normal.dot(x));
    hi_mm = std::max(hi_mm, normal.dot(x));
  }
  const double d_mm = offset_m * 1e3;
  const double gap_mm = std::max({lo_mm - d_mm, d_mm - hi_mm, 0.0});
  if (!(gap_mm <= kNearCtMm))
    fail(file, field,
         fmt::format("the plane ({:.1f} mm along its normal) passes {:.1f} mm from {} (at most {:.0f} mm outside it "
                     "is allowed: the organ rests on it)",
                     d_mm, gap_mm, box.name, kNearCtMm));
}

void write_fiducials(const std::vector<Eigen::Vector3d>& fiducials_m, const std::string& path) {
  Json centres = Json::array();
  for (const Eigen::Vector3d& f : fiducials_m) centres.push_back({f.x() * 1e3, f.y() * 1e3, f.z() * 1e3});
  const Json doc = {{"format", kFiducialsFormat}, {"version", kCaseVersion}, {"centres_mm", centres}};
  std::ofstream out(path);
  out << doc.dump(1) << '\n';
  if (!out) throw CaseError(path + ": cannot write");
}

// the tissue map's names as case.json may hold them: 1 to kMaxTissueNames, each non-empty, at
// most kMaxTissueNameChars, no control characters (a name is one line of the colour table)
std::string tissue_names_problem(const std::vector<std::string>& names) {
  if (names.empty() || names.size() > static_cast<size_t>(kMaxTissueNames))
    return fmt::format("expected 1 to {} names, one per label (label 0 first); got {}", kMaxTissueNames, names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string& n = names[i];
    const bool control =
        std::any_of(n.begin(), n.end(), [](char ch) { return static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f; });
    if (n.empty() || n.size() > static_cast<size_t>(kMaxTissueNameChars) || control)
      return fmt::format("names[{}]: expected a non-empty name of at most {} characters, no control characters", i,
                         kMaxTissueNameChars);
  }
  return "";
}

// a 3D Slicer colour table for the tissue map (label, name, R G B A per line; written for
// viewing, not read): each tissue a distinct hue, label 0 transparent
void write_tissue_colors(const std::vector<std::string>& names, const std::string& path) {
  std::ofstream out(path);
  out << "# pcisim tissue labels (tissue.nrrd)\n";
  for (size_t i = 0; i < names.size(); ++i) {
    // hues a golden angle apart, so neighbouring labels differ
    const double hue = std::fmod(0.618033988749895 * static_cast<double>(i), 1.0) * 6.0;
    const double x = 1.0 - std::abs(std::fmod(hue, 2.0) - 1.0);
    const double rgb[6][3] = {{1, x, 0}, {x, 1, 0}, {0, 1, x}, {0, x, 1}, {x, 0, 1}, {1, 0, x}};
    const double* c = rgb[static_cast<int>(hue) % 6];
    std::string name = names[i];
    std::replace(name.begin(), name.end(), ' ', '_');  // Slicer's table separates by spaces
    out << fmt::format("{} {} {} {} {} {}\n", i, name, std::lround(55 + 200 * c[0]), std::lround(55 + 200 * c[1]),
                       std::lround(55 + 200 * c[2]), i == 0 ? 0 : 255);
  }
  if (!out) throw CaseError(path + ": cannot write");
}

// the organ's files and support (case.json "organ"; docs/anatomy.md)
Json write_organ(const Organ& o, const fs::path& dir) {
  // a PLY whose millimetres read back to the same doubles, not an STL's floats: the particle
  // model physics builds is not continuous in the surface's last bits (particles, clusters and
  // tets lie on a lattice from the bounding box, and points exactly on a cell's edge go one way
  // or the other), so a written phantom runs as the procedural one only when it is bit for bit
  write_ply_mm(o.surface, (dir / "organ.ply").string(), "pcisim organ");
  Json doc = {{"name", o.name}, {"surface", "organ.ply"}};
  if (!o.fiducials_m.empty()) {
    write_fiducials(o.fiducials_m, (dir / "fiducials.json").string());
    doc["fiducials"] = "fiducials.json";
    // for 3D Slicer: the beads as a point list (written for viewing, not read)
    write_markups_fiducials(o.name.empty() ? "F" : o.name, o.fiducials_m, (dir / "slicer/fiducials.mrk.json").string());
    doc["slicer_fiducials"] = "slicer/fiducials.mrk.json";
  }
  if (o.tissue) {
    // the CT's grid and int16 labels: a 3D Slicer labelmap, with its colour table beside it
    write_nrrd(o.tissue->labels, (dir / "tissue.nrrd").string(), volume_io_has_gzip());
    doc["tissue"] = {{"labels", "tissue.nrrd"}, {"names", o.tissue->names}};
    write_tissue_colors(o.tissue->names, (dir / "slicer/tissue.ctbl").string());
    doc["tissue"]["slicer_colors"] = "slicer/tissue.ctbl";
  }
  const Eigen::Vector3d n = o.support_normal.array() + 0.0;  // -0 written as 0
  doc["support"] = {{"normal", {n.x(), n.y(), n.z()}}, {"offset_mm", o.support_offset_m * 1e3}};
  return doc;
}

// the bead centres of fiducials.json, metres; each one inside the organ's surface
std::vector<Eigen::Vector3d> read_fiducials(const std::string& file, const TriangleMesh& surface,
                                            const std::string& surface_file) {
  std::vector<Eigen::Vector3d> fiducials_m;
  try {
    const Json doc = json::parse_json_checked(io::read_file(file, kMaxFiducialsFileBytes), file);
    json::JsonReader r(doc, "");
    if (r.text("format", "") != kFiducialsFormat) r.fail("format", fmt::format("expected \"{}\"", kFiducialsFormat));
    r.integer("version", 0, kCaseVersion, kCaseVersion);
    const Json& centres = r.list("centres_mm");
    // each bead is tested against every triangle of the surface below
    if (centres.size() > static_cast<size_t>(kMaxFiducials))
      r.fail("centres_mm", fmt::format("{} beads, more than {} (the limit)", centres.size(), kMaxFiducials));
    for (size_t i = 0; i < centres.size(); ++i) {
      const Json& c = centres[i];
      bool ok = c.is_array() && c.size() == 3;
      for (size_t a = 0; ok && a < 3; ++a) ok = c[a].is_number() && std::isfinite(c[a].get<double>());
      if (!ok) r.fail(fmt::format("centres_mm[{}]", i), "expected [x, y, z] in millimetres");
      fiducials_m.emplace_back(1e-3 * Eigen::Vector3d(c[0].get<double>(), c[1].get<double>(), c[2].get<double>()));
    }
    r.finish();
  } catch (const json::JsonError& e) {
    throw CaseError(fmt::format("{}: {}", file, e.what()));
  } catch (const VolumeIoError& e) {
    throw CaseError(e.what());
  }
  // inside = winding number 1 about the bead (the surface is closed and wound outward, checked
  // before): an exact test, not the bounding box's
  for (size_t i = 0; i < fiducials_m.size(); ++i) {
    const double w = winding_number(surface, fiducials_m[i]);
    if (!(w > 0.5)) {
      const Eigen::Vector3d p_mm = fiducials_m[i] * 1e3;
      fail(file, fmt::format("centres_mm[{}]", i),
           fmt::format("at ({:.1f}, {:.1f}, {:.1f}) mm, outside the organ's surface {} (winding number {:.2f})",
                       p_mm.x(), p_mm.y(), p_mm.z(), fs::path(surface_file).filename().string(),
                       std::round(w * 100) / 100 + 0.0));  // + 0.0: never "-0.00"
    }
  }
  return fiducials_m;
}

void write_lesions(const std::vector<Lesion>& lesions, const std::string& path) {
  Json list = Json::array();
  for (const Lesion& l : lesions)
    list.push_back({{"branch", l.branch},
                    {"position_mm", l.position_mm},
                    {"length_mm", l.length_mm},
                    {"minimal_lumen_diameter_mm", l.minimal_lumen_diameter_mm},
                    {"reference_diameter_mm", l.reference_diameter_mm},
                    {"diameter_stenosis_pct", l.diameter_stenosis_pct},
                    {"calcified_fraction", l.calcified_fraction},
                    {"eccentricity", l.eccentricity}});
  std::ofstream out(path);
  out << Json{{"format", kLesionsFormat}, {"version", kCaseVersion}, {"lesions", list}}.dump(2) << '\n';
  if (!out) throw CaseError(path + ": cannot write");
}

// lesions.json: each lesion on a branch of the case's vessels, within it, its figures consistent
std::vector<Lesion> read_lesions(const std::string& file, const VesselTree& tree) {
  std::vector<Lesion> lesions;
  try {
    const Json doc = json::parse_json_checked(io::read_file(file, kMaxLesionsFileBytes), file);
    json::JsonReader r(doc, "");
    if (r.text("format", "") != kLesionsFormat) r.fail("format", fmt::format("expected \"{}\"", kLesionsFormat));
    r.integer("version", 0, kCaseVersion, kCaseVersion);
    if (!r.has("lesions")) r.fail("lesions", "missing (a list of lesions, empty for none)");
    const Json& list = r.list("lesions");
    if (list.size() > static_cast<size_t>(kMaxLesions))
      r.fail("lesions", fmt::format("{} lesions, more than {} (the limit)", list.size(), kMaxLesions));
    for (size_t i = 0; i < list.size(); ++i) {
      json::JsonReader lr(list[i], fmt::format("lesions[{}]", i));
      for (const char* key : {"branch", "position_mm", "length_mm", "minimal_lumen_diameter_mm",
                              "reference_diameter_mm", "diameter_stenosis_pct"})
        if (!lr.has(key)) lr.fail(key, "missing");
      Lesion l;
      l.branch = lr.text("branch", "");
      l.position_mm = lr.number("position_mm", -1.0, 0.0, 1e4);
      l.length_mm = lr.number("length_mm", -1.0, 0.0, 1e4);
      l.minimal_lumen_diameter_mm = lr.number("minimal_lumen_diameter_mm", -1.0, 0.0, 50.0);
      l.reference_diameter_mm = lr.number("reference_diameter_mm", -1.0, 0.0, 50.0);
      l.diameter_stenosis_pct = lr.number("diameter_stenosis_pct", -1.0, 0.0, 100.0);
      l.calcified_fraction = lr.number("calcified_fraction", 0.0, 0.0, 1.0);
      l.eccentricity = lr.number("eccentricity", 0.0, 0.0, 1.0);
      lr.finish();
      if (const std::string why = validate_lesion(l, tree); !why.empty())
        throw json::JsonError(fmt::format("lesions[{}].{}", i, why));
      lesions.push_back(l);
    }
    r.finish();
  } catch (const json::JsonError& e) {
    throw CaseError(fmt::format("{}: {}", file, e.what()));
  } catch (const VolumeIoError& e) {
    throw CaseError(e.what());
  }
  return lesions;
}

// the signed volume of a closed surface (positive when wound counter-clockwise seen from outside)
double signed_volume_m3(const TriangleMesh& m) {
  double six_v = 0.0;
  for (const auto& t : m.triangles) six_v += m.vertices_m[t[0]].dot(m.vertices_m[t[1]].cross(m.vertices_m[t[2]]));
  return six_v / 6.0;
}

// case.json "organ": its surface (closed, manifold, wound outward), its beads (inside it) and the
// support it rests on (a unit normal out of the support, the organ on its free side)
Organ read_organ(json::JsonReader o, const fs::path& dir, const std::string& case_json, std::string* surface_file,
                 std::string* tissue_file) {
  Organ organ;
  organ.name = o.text("name", "organ");
  if (organ.name.empty()) o.fail("name", "expected a non-empty name");
  *surface_file = member_file(dir, case_json, "organ.surface", o.text("surface", ""));
  organ.surface = read_mesh(*surface_file, kMillimetre, kMaxOrganTriangles);
  if (organ.surface.triangles.empty()) fail(*surface_file, "mesh", "no triangles (the organ needs its surface)");
  check_mesh_coordinates(organ.surface, *surface_file);
  if (const std::string why = check_closed_manifold(organ.surface); !why.empty())
    fail(*surface_file, "mesh", why + " (the organ must be a closed, manifold surface)");
  if (signed_volume_m3(organ.surface) <= 0.0)
    fail(*surface_file, "mesh",
         "wound inside out (its volume is negative: faces must run counter-clockwise seen from outside)");
  if (o.has("fiducials")) {
    const std::string file = member_file(dir, case_json, "organ.fiducials", o.text("fiducials", ""));
    organ.fiducials_m = read_fiducials(file, organ.surface, *surface_file);
  }
  if (!o.has("support"))
    o.fail("support", "missing (the plane the organ rests on: {\"normal\": [x, y, z], \"offset_mm\": d})");
  json::JsonReader s = o.child("support");
  Eigen::Vector3d n;
  if (!s.numbers("normal", {n.data(), 3})) s.fail("normal", "expected [x, y, z], a direction out of the support");
  // bounded before it is normalised: the norm of [0, -1e308, 0] overflows to inf, and the normal
  // became 0 (refused only later, by the soft-tissue effect, naming no file)
  if (!n.allFinite() || n.cwiseAbs().maxCoeff() > kMaxDirectionComponent)
    s.fail("normal", fmt::format("expected a direction whose components are within +-{:g} (any length; got [{:g}, "
                                 "{:g}, {:g}])",
                                 kMaxDirectionComponent, n.x(), n.y(), n.z()));
  if (!(n.norm() >= kMinDirectionLength))
    s.fail("normal", fmt::format("expected a non-zero direction (out of the support, toward the organ; at least {:g} "
                                 "long)",
                                 kMinDirectionLength));
  organ.support_normal = n.normalized();
  if (!s.has("offset_mm"))
    s.fail("offset_mm", "missing (the plane's signed distance from the origin along the normal)");
  organ.support_offset_m = 1e-3 * s.number("offset_mm", 0.0, -1e5, 1e5);
  s.finish();
  // a normal the wrong way round puts the organ inside its support
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& v : organ.surface.vertices_m) centre += v;
  centre /= static_cast<double>(organ.surface.vertices_m.size());
  const double above_mm = 1e3 * (organ.support_normal.dot(centre) - organ.support_offset_m);
  if (above_mm < 0.0)
    o.fail("support", fmt::format("the organ's centre lies {:.1f} mm inside the support (the normal points out of the "
                                  "support, toward the organ)",
                                  -above_mm));
  if (o.has("tissue")) {
    // the labels are read with the CT (they must lie on its grid); their names here
    json::JsonReader t = o.child("tissue");
    *tissue_file = member_file(dir, case_json, "organ.tissue.labels", t.text("labels", ""));
    const auto& names = t.list("names");
    if (names.size() > static_cast<size_t>(kMaxTissueNames))
      t.fail("names", fmt::format("{} names, more than {} (the limit)", names.size(), kMaxTissueNames));
    TissueMap map;
    for (const auto& n : names) {
      if (!n.is_string()) t.fail("names", fmt::format("names[{}]: expected a string", map.names.size()));
      map.names.push_back(n.get<std::string>());
    }
    if (const std::string why = tissue_names_problem(map.names); !why.empty()) t.fail("names", why);
    t.text("slicer_colors", "");  // written for viewers, not read
    t.finish();
    organ.tissue = std::move(map);
  }
  o.text("slicer_fiducials", "");  // written for viewers, not read
  o.finish();
  return organ;
}

}  // namespace

void write_lesions_json(const std::vector<Lesion>& lesions, const std::string& path) {
  write_lesions(lesions, path);
}

std::vector<Lesion> read_lesions_json(const std::string& path, const VesselTree& tree) {
  return read_lesions(path, tree);
}

void write_case(const Case& c, const std::string& dir_name) {
  const fs::path dir(dir_name);
  // a tissue map that would be refused on reading is not written (checked before any file is)
  if (c.organ && c.organ->tissue) {
    std::string why = tissue_names_problem(c.organ->tissue->names);
    if (why.empty()) why = c.ct ? validate_tissue_map(*c.organ->tissue, *c.ct) : "the case has no CT";
    if (!why.empty()) throw CaseError(fmt::format("{}: {}", (dir / "tissue.nrrd").string(), why));
  }
  std::error_code ec;
  fs::create_directories(dir / "slicer", ec);
  if (ec) throw CaseError(fmt::format("{}: cannot create the case folder ({})", dir_name, ec.message()));
  Json doc = {{"format", kCaseFormat}, {"version", kCaseVersion}, {"name", c.name}, {"units", "mm"}, {"frame", "LPS"}};
  // an organ case may have no vessels (an empty tree is no vessels.json)
  if (!c.vessels.branches.empty()) {
    write_vessel_tree_json(c.vessels, (dir / "vessels.json").string());
    doc["vessels"] = "vessels.json";
  }
  if (!c.lesions.empty()) {
    // a case that would be refused on reading is not written
    for (size_t i = 0; i < c.lesions.size(); ++i)
      if (const std::string why = validate_lesion(c.lesions[i], c.vessels); !why.empty())
        throw CaseError(fmt::format("{}: lesions[{}].{}", (dir / "lesions.json").string(), i, why));
    write_lesions(c.lesions, (dir / "lesions.json").string());
    doc["lesions"] = "lesions.json";
  }
  if (!c.lumen.triangles.empty()) {
    write_stl(c.lumen, (dir / "lumen.stl").string(), "pcisim lumen");
    doc["lumen"] = "lumen.stl";
  }
  if (c.ct) {
    write_nrrd(*c.ct, (dir / "ct.nrrd").string(), volume_io_has_gzip());
    doc["ct"] = {{"file", "ct.nrrd"}, {"lumen_enhanced", c.ct_lumen_enhanced}};
  }
  if (c.organ) doc["organ"] = write_organ(*c.organ, dir);
  Json landmarks = Json::array();
  for (const auto& l : c.landmarks)
    landmarks.push_back({{"name", l.name}, {"position_m", {l.position_m.x(), l.position_m.y(), l.position_m.z()}}});
  doc["landmarks"] = landmarks;
  // where the template heart sits (docs/anatomy.md); the phantom's is the identity
  if (!c.heart.is_identity() || c.heart_vertices_m.cols() > 0) {
    Json rot = Json::array();
    for (int i = 0; i < 3; ++i) rot.push_back({c.heart.rotation(i, 0), c.heart.rotation(i, 1), c.heart.rotation(i, 2)});
    const Eigen::Vector3d& t = c.heart.translation_m;
    doc["heart"] = {{"template", "pcisim-template-heart"},
                    {"rotation", rot},
                    {"scale", c.heart.scale},
                    {"translation_m", {t.x(), t.y(), t.z()}}};
    // the template's rest shape fitted to the patient (template frame, TetGen .node in mm)
    if (c.heart_vertices_m.cols() > 0) {
      std::ofstream node(dir / "heart.node");
      write_tetgen_nodes(c.heart_vertices_m, node);
      if (!node) throw CaseError((dir / "heart.node").string() + ": cannot write");
      doc["heart"]["rest_vertices"] = "heart.node";
    }
  }
  // for 3D Slicer: each centerline as a markups curve (the lumen and CT open as they are). The
  // file is named after the branch made safe (never a path out of slicer/), and kept distinct
  // from the others' even on a case-insensitive file system ("a/b" and "a_b": a_b, a_b-2)
  Json curves = Json::array();
  std::set<std::string> taken;
  for (const auto& b : c.vessels.branches) {
    const std::string stem = markups_file_stem(b.name);
    std::string unique = stem;
    for (int k = 2; !taken.insert(lower_ascii(unique)).second; ++k) unique = fmt::format("{}-{}", stem, k);
    const std::string name = "slicer/" + unique + ".mrk.json";
    write_markups_curve(b, (dir / name).string());
    curves.push_back(name);
  }
  doc["slicer_centerlines"] = curves;
  // a picture for people: front and side views of the CT with the vessels over it (only when
  // built with libpng; case_overview_written() says so to callers that log)
#ifdef PCISIM_ANATOMY_HAVE_PNG
  write_case_overview(c, (dir / "overview.png").string());
  doc["overview"] = "overview.png";
#endif
  std::ofstream out(dir / "case.json");
  out << doc.dump(2) << '\n';
  if (!out) throw CaseError((dir / "case.json").string() + ": cannot write");
}

Case read_case(const std::string& dir_name, const DicomFolderReader& read_dicom) {
  const fs::path dir(dir_name);
  const std::string case_json = (dir / "case.json").string();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw CaseError(fmt::format("{}: not a case folder (no such directory)", dir_name));
  if (!fs::exists(fs::symlink_status(case_json, ec)))
    throw CaseError(fmt::format("{}: missing (a case folder needs case.json)", case_json));
  if (const InsideFolder inside = resolve_inside_folder(dir_name, "case.json"); inside.escape != FolderEscape::kNone)
    throw CaseError(fmt::format("{}: {} (a case reads nothing outside its folder)", case_json, inside.why));
  if (const std::string why = json::regular_file_problem(case_json, "case.json"); !why.empty()) throw CaseError(why);
  // read before the try below, whose messages add case.json's path (this one names it already)
  std::string case_text;
  try {
    case_text = io::read_file(case_json, kMaxCaseJsonBytes);
  } catch (const VolumeIoError& e) {
    throw CaseError(e.what());
  }
  Case c;
  std::string vessels_file, ct_file, ct_dicom, organ_surface_file, tissue_file, lesions_file;
  try {
    const Json doc = json::parse_json_checked(case_text, case_json);
    json::JsonReader r(doc, "");
    if (r.text("format", "") != kCaseFormat) r.fail("format", fmt::format("expected \"{}\"", kCaseFormat));
    // what the numbers mean is never guessed: version, units and frame must be stated
    for (const char* field : {"version", "units", "frame"})
      if (!r.has(field)) fail(case_json, field, "missing");
    r.integer("version", 0, kCaseVersion, kCaseVersion);
    c.name = r.text("name", dir.filename().string());
    r.text("units", "", {"mm"});
    r.text("frame", "", {"LPS"});
    // a coronary case needs its vessels; an organ case may have none
    if (!r.has("organ") || r.has("vessels"))
      vessels_file = member_file(dir, case_json, "vessels", r.text("vessels", ""));
    if (r.has("organ")) {
      c.organ = read_organ(r.child("organ"), dir, case_json, &organ_surface_file, &tissue_file);
      if (!r.has("ct")) fail(case_json, "ct", "missing (an organ case needs a CT: the ultrasound images it)");
    }
    if (r.has("lumen")) {
      const std::string lumen_file = member_file(dir, case_json, "lumen", r.text("lumen", ""));
      c.lumen = read_mesh(lumen_file, kMillimetre, kMaxLumenTriangles);
      check_mesh_coordinates(c.lumen, lumen_file);
      if (const std::string why = check_closed_manifold(c.lumen); !why.empty())
        fail(lumen_file, "mesh", why + " (the lumen must be a closed, manifold surface)");
    }
    if (r.has("ct")) {
      json::JsonReader ct = r.child("ct");
      // a volume file, or a DICOM series folder
      if (ct.has("dicom") == ct.has("file"))
        ct.fail("file", "expected either \"file\" (NRRD/MetaImage) or \"dicom\" (a series folder)");
      if (ct.has("file")) ct_file = member_file(dir, case_json, "ct.file", ct.text("file", ""));
      if (ct.has("dicom")) {
        const std::string name = ct.text("dicom", "");
        check_inside(dir, case_json, "ct.dicom", name, "folder");
        ct_dicom = (dir / name).string();
        if (!fs::is_directory(ct_dicom, ec))
          fail(case_json, "ct.dicom", fmt::format("folder '{}' not found in {}", name, dir.string()));
        if (!read_dicom) fail(case_json, "ct.dicom", "this program was built without the DICOM reader (ITK)");
      }
      c.ct_lumen_enhanced = ct.boolean("lumen_enhanced", true);
      ct.finish();
    }
    if (r.list("landmarks").size() > static_cast<size_t>(kMaxLandmarks))
      r.fail("landmarks",
             fmt::format("{} landmarks, more than {} (the limit)", r.list("landmarks").size(), kMaxLandmarks));
    for (const auto& l : r.list("landmarks")) {
      json::JsonReader lr(l, "landmarks[]");
      Landmark m;
      m.name = lr.text("name", "");
      const auto& p = lr.list("position_m");
      if (m.name.empty()) lr.fail("name", "expected a non-empty name");
      if (p.size() != 3 || !p[0].is_number() || !p[1].is_number() || !p[2].is_number())
        lr.fail("position_m", "expected [x, y, z] in metres");
      m.position_m = {p[0].get<double>(), p[1].get<double>(), p[2].get<double>()};
      lr.finish();
      c.landmarks.push_back(m);
    }
    if (r.has("heart")) {
      json::JsonReader h = r.child("heart");
      h.text("template", "", {"pcisim-template-heart"});
      c.heart.scale = h.number("scale", 1.0, 0.5, 2.0);
      const auto& rot = h.list("rotation");
      const auto& t = h.list("translation_m");
      auto numbers = [](const nlohmann::json& a, size_t n) {
        if (!a.is_array() || a.size() != n) return false;
        for (const auto& x : a)
          if (!x.is_number()) return false;
        return true;
      };
      if (rot.size() != 3 || !numbers(rot[0], 3) || !numbers(rot[1], 3) || !numbers(rot[2], 3))
        h.fail("rotation", "expected three rows of three numbers");
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) c.heart.rotation(i, j) = rot[i][j].get<double>();
      // a proper rotation: orthonormal, determinant +1 (to the precision JSON keeps)
      if ((c.heart.rotation.transpose() * c.heart.rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() >
              1e-6 ||
          c.heart.rotation.determinant() < 0)
        h.fail("rotation", "expected a rotation (orthonormal rows, determinant +1)");
      if (!numbers(t, 3) || std::abs(t[0].get<double>()) > kMaxCoordinateM ||
          std::abs(t[1].get<double>()) > kMaxCoordinateM || std::abs(t[2].get<double>()) > kMaxCoordinateM)
        h.fail("translation_m", fmt::format("expected [x, y, z] in metres, each within {:.0f} m", kMaxCoordinateM));
      c.heart.translation_m = {t[0].get<double>(), t[1].get<double>(), t[2].get<double>()};
      if (h.has("rest_vertices")) {
        // one vertex per template vertex, near the template (a fit moves the surface by
        // millimetres, never by a heart's size): a file of another mesh or in metres is refused
        const std::string node_file = member_file(dir, case_json, "heart.rest_vertices", h.text("rest_vertices", ""));
        try {
          const std::string text = io::read_file(node_file, kMaxHeartNodeFileBytes);
          c.heart_vertices_m = parse_tetgen_nodes({text, node_file}, 1e-3);
        } catch (const std::invalid_argument& e) {
          throw CaseError(e.what());
        }
        const Eigen::Matrix3Xd& tv = template_heart_mesh().vertices_m;
        if (c.heart_vertices_m.cols() != tv.cols())
          fail(node_file, "nodes",
               fmt::format("{} vertices, the template heart has {} (a fitted rest shape keeps the template's tets)",
                           c.heart_vertices_m.cols(), tv.cols()));
        const double worst_mm = 1e3 * (c.heart_vertices_m - tv).colwise().norm().maxCoeff();
        if (!(worst_mm <= kMaxFittedHeartMoveMm))
          fail(node_file, "nodes",
               fmt::format("a vertex {:.1f} mm from the template's (more than {:.0f} mm: not a fit of the template "
                           "heart in its frame, in mm)",
                           worst_mm, kMaxFittedHeartMoveMm));
      }
      h.finish();
    }
    if (r.has("lesions")) lesions_file = member_file(dir, case_json, "lesions", r.text("lesions", ""));
    r.list("slicer_centerlines");  // written for viewers, not needed to simulate
    r.text("overview", "");        // a picture for people
    r.finish();
  } catch (const json::JsonError& e) {
    throw CaseError(fmt::format("{}: {}", case_json, e.what()));
  } catch (const MeshIoError& e) {
    throw CaseError(e.what());
  } catch (const std::runtime_error& e) {
    if (dynamic_cast<const CaseError*>(&e)) throw;
    throw CaseError(fmt::format("{}: {}", case_json, e.what()));
  }
  if (!vessels_file.empty()) {
    try {
      c.vessels = read_vessel_tree_json(vessels_file);
    } catch (const std::runtime_error& e) {
      throw CaseError(e.what());
    }
  }
  if (!lesions_file.empty()) {
    if (c.vessels.branches.empty()) fail(case_json, "lesions", "lesions need the case's vessels (vessels.json)");
    c.lesions = read_lesions(lesions_file, c.vessels);
  }
  if (!ct_file.empty()) {
    try {
      // a detached data file too must lie beside the header, inside the case
      c.ct = read_volume(ct_file, /*require_spacing=*/true, DataFileScope::kHeaderFolder);
    } catch (const VolumeIoError& e) {
      throw CaseError(e.what());
    }
  }
  if (!ct_dicom.empty()) {
    try {
      c.ct = read_dicom(ct_dicom);
    } catch (const std::runtime_error& e) {
      throw CaseError(e.what());
    }
    ct_file = ct_dicom;
  }
  if (c.ct) check_vessels_inside(c.vessels, *c.ct, vessels_file, ct_file);
  if (c.organ) check_organ_inside(c.organ->surface, *c.ct, organ_surface_file, ct_file);
  if (!tissue_file.empty()) {
    try {
      c.organ->tissue->labels = read_volume(tissue_file, /*require_spacing=*/true, DataFileScope::kHeaderFolder);
    } catch (const VolumeIoError& e) {
      throw CaseError(e.what());
    }
    if (const std::string why = validate_tissue_map(*c.organ->tissue, *c.ct); !why.empty())
      throw CaseError(fmt::format("{}: {} (case.json organ.tissue; the CT is {})", tissue_file, why, ct_file));
  }
  // the numbers of case.json that place things: in or near the CT (a heart centre 5 m away ran
  // and wrote samples of nothing)
  const NearBox box = near_box(c, ct_file, vessels_file);
  for (size_t i = 0; i < c.landmarks.size(); ++i)
    check_near(box, c.landmarks[i].position_m, case_json, fmt::format("landmarks[{}].position_m", i),
               fmt::format("landmark \"{}\"", c.landmarks[i].name));
  if (!c.heart.is_identity())
    check_near(box, c.heart.translation_m, case_json, "heart.translation_m", "the heart's centre");
  if (c.organ)
    check_plane_near(box, c.organ->support_normal, c.organ->support_offset_m, case_json, "organ.support.offset_mm");
  return c;
}

}  // namespace pcisim::anatomy
