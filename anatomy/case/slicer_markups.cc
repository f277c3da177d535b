#include "anatomy/case/slicer_markups.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace pcisim::anatomy {

std::string markups_file_stem(const std::string& branch_name) {
  std::string stem = branch_name.substr(0, 100);
  for (char& c : stem)
    if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-')) c = '_';
  return stem.empty() ? "branch" : stem;
}

void write_markups_curve(const VesselBranch& branch, const std::string& path) {
  using nlohmann::json;
  json points = json::array();
  for (size_t i = 0; i < branch.points.size(); ++i) {
    const Eigen::Vector3d p = branch.points[i].position_m * 1e3;
    points.push_back({{"id", std::to_string(i + 1)},
                      {"label", branch.name + "-" + std::to_string(i + 1)},
                      {"position", {p.x(), p.y(), p.z()}},
                      {"positionStatus", "defined"}});
  }
  const json doc = {{"@schema",
                     "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/"
                     "markups-schema-v1.0.3.json#"},
                    {"markups",
                     {{{"type", "Curve"},
                       {"coordinateSystem", "LPS"},
                       {"coordinateUnits", "mm"},
                       {"locked", true},
                       {"labelFormat", branch.name + "-%d"},
                       {"controlPoints", points},
                       {"display", {{"pointLabelsVisibility", false}, {"glyphScale", 0.5}}}}}}};
  std::ofstream out(path);
  out << doc.dump(1) << '\n';
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace pcisim::anatomy
