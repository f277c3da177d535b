#include "anatomy/case/slicer_markups.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

namespace pcisim::anatomy {

std::string markups_file_stem(const std::string& branch_name) {
  std::string stem = branch_name.substr(0, 100);
  for (char& c : stem)
    if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-')) c = '_';
  return stem.empty() ? "branch" : stem;
}

namespace {

using nlohmann::json;

// control points at these positions (metres in, mm out), labelled <name>-1, -2, ...
json control_points(const std::string& name, std::span<const Eigen::Vector3d> points_m) {
  json points = json::array();
  for (size_t i = 0; i < points_m.size(); ++i) {
    const Eigen::Vector3d p = points_m[i] * 1e3;
    points.push_back({{"id", std::to_string(i + 1)},
                      {"label", name + "-" + std::to_string(i + 1)},
                      {"position", {p.x(), p.y(), p.z()}},
                      {"positionStatus", "defined"}});
  }
  return points;
}

// one markups node of `type` ("Curve", "Fiducial") in LPS mm, locked
void write_markups(const std::string& type, const std::string& name, const json& points, double glyph_scale,
                   const std::string& path) {
  const json doc = {{"@schema",
                     "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/"
                     "markups-schema-v1.0.3.json#"},
                    {"markups",
                     {{{"type", type},
                       {"coordinateSystem", "LPS"},
                       {"coordinateUnits", "mm"},
                       {"locked", true},
                       {"labelFormat", name + "-%d"},
                       {"controlPoints", points},
                       {"display", {{"pointLabelsVisibility", false}, {"glyphScale", glyph_scale}}}}}}};
  std::ofstream out(path);
  out << doc.dump(1) << '\n';
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace

void write_markups_curve(const VesselBranch& branch, const std::string& path) {
  std::vector<Eigen::Vector3d> points_m;
  points_m.reserve(branch.points.size());
  for (const auto& p : branch.points) points_m.push_back(p.position_m);
  write_markups("Curve", branch.name, control_points(branch.name, points_m), 0.5, path);
}

void write_markups_fiducials(const std::string& name, std::span<const Eigen::Vector3d> points_m,
                             const std::string& path) {
  write_markups("Fiducial", name, control_points(name, points_m), 1.0, path);
}

}  // namespace pcisim::anatomy
