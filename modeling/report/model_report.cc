#include "modeling/report/model_report.h"

#include <fmt/format.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace pcisim::modeling {

double peak_memory_mib() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // kB
  }
  return 0.0;
}

void write_model_report(const std::string& path, const std::string& ct_source, const anatomy::Volume& ct,
                        const std::vector<Eigen::Vector3d>& seeds_mm, const CtaModel& model, double total_s) {
  using nlohmann::json;
  json doc = {{"format", "pcisim-model-report"}, {"version", 1}};
  json dir = json::array();
  for (int r = 0; r < 3; ++r) dir.push_back({ct.direction(r, 0), ct.direction(r, 1), ct.direction(r, 2)});
  doc["input"] = {{"ct", ct_source},
                  {"dims", {ct.dims[0], ct.dims[1], ct.dims[2]}},
                  {"spacing_mm", {ct.spacing_mm.x(), ct.spacing_mm.y(), ct.spacing_mm.z()}},
                  {"origin_mm", {ct.origin_mm.x(), ct.origin_mm.y(), ct.origin_mm.z()}},
                  {"direction", dir}};
  json seeds = json::array();
  for (const auto& s : seeds_mm) seeds.push_back({s.x(), s.y(), s.z()});
  doc["seeds_mm"] = seeds;
  json stages = json::array();
  for (const StageReport& s : model.stages) {
    json figures = json::object();
    for (const auto& [k, v] : s.figures) figures[k] = v;
    stages.push_back({{"name", s.name}, {"seconds", s.seconds}, {"figures", figures}, {"notes", s.notes}});
  }
  doc["stages"] = stages;
  json branches = json::array();
  for (const auto& b : model.model.vessels.branches) {
    double len = anatomy::branch_length_m(b) * 1e3, sum = 0, least = 1e300;
    for (const auto& p : b.points) {
      sum += p.radius_m * 1e3;
      least = std::min(least, p.radius_m * 1e3);
    }
    branches.push_back({{"name", b.name},
                        {"parent", b.parent},
                        {"length_mm", len},
                        {"mean_radius_mm", b.points.empty() ? 0.0 : sum / b.points.size()},
                        {"least_radius_mm", b.points.empty() ? 0.0 : least},
                        {"points", b.points.size()}});
  }
  doc["branches"] = branches;
  doc["total_seconds"] = total_s;
  doc["peak_memory_mib"] = peak_memory_mib();
  std::ofstream out(path);
  out << doc.dump(2) << '\n';
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace pcisim::modeling
