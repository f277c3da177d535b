#include "modeling/cta/branch_checks.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include "realtime/percentile.h"

namespace pcisim::modeling {
namespace {

// median of the centre HU over samples [from, to) with radius >= min_r; NaN when none qualifies
double median_hu(const ModelBranch& b, const FloatImage& hu, size_t from, size_t to, double min_r) {
  std::vector<double> v;
  for (size_t i = from; i < std::min(to, b.points_mm.size()); ++i) {
    if (b.radius_mm[i] < min_r) continue;
    v.push_back(hu.at(hu.grid.continuous_index(b.points_mm[i]), -1000.0f));
  }
  if (v.empty()) return std::nan("");
  return realtime::upper_median_in_place(std::span<double>(v));
}

}  // namespace

std::vector<std::string> drop_dark_branches(ModelTree* tree, const FloatImage& hu, const BranchCheckOptions& o) {
  std::vector<std::string> notes;
  auto& b = tree->branches;
  std::vector<bool> drop(b.size(), false);
  for (size_t i = 1; i < b.size(); ++i) {
    const ModelBranch& c = b[i];
    if (c.parent < 0 || drop[c.parent]) {
      drop[i] = c.parent >= 0 && drop[c.parent];
      continue;
    }
    const ModelBranch& p = b[c.parent];
    // the parent within 10 samples of the junction, the child beyond its first 4 samples
    const size_t j = static_cast<size_t>(std::max(0, c.parent_point));
    const double parent_hu = median_hu(p, hu, j > 10 ? j - 10 : 0, j + 10, o.min_radius_mm);
    const double child_hu = median_hu(c, hu, 4, c.points_mm.size(), o.min_radius_mm);
    if (std::isnan(parent_hu) || std::isnan(child_hu)) continue;
    if (child_hu - o.tissue_hu < o.vein_hu_ratio * (parent_hu - o.tissue_hu)) {
      drop[i] = true;
      const Eigen::Vector3d& at = c.points_mm.front();
      notes.push_back(fmt::format(
          "cut away a branch of {} samples leaving at ({:.1f}, {:.1f}, {:.1f}) mm: its lumen is {:.0f} HU against "
          "{:.0f} HU in the vessel it touches (a vein, not an artery)",
          c.points_mm.size(), at.x(), at.y(), at.z(), child_hu, parent_hu));
    }
  }
  // keep the rest, re-indexing parents
  std::vector<int> index(b.size(), -1);
  std::vector<ModelBranch> kept;
  for (size_t i = 0; i < b.size(); ++i) {
    if (drop[i]) continue;
    index[i] = static_cast<int>(kept.size());
    kept.push_back(b[i]);
    if (kept.back().parent >= 0) kept.back().parent = index[kept.back().parent];
  }
  b = std::move(kept);
  return notes;
}

std::vector<std::string> find_abrupt_ends(const ModelTree& tree, const BranchCheckOptions& o) {
  std::vector<std::string> notes;
  const auto& b = tree.branches;
  for (size_t i = 0; i < b.size(); ++i) {
    const bool leaf = std::none_of(b.begin(), b.end(), [&](const ModelBranch& c) {
      return c.parent == static_cast<int>(i) && c.parent_point + 3 >= static_cast<int>(b[i].points_mm.size());
    });
    if (!leaf || b[i].points_mm.size() < 4) continue;
    const size_t n = b[i].points_mm.size();
    const double r = (b[i].radius_mm[n - 2] + b[i].radius_mm[n - 3] + b[i].radius_mm[n - 4]) / 3.0;
    if (r < o.abrupt_end_radius_mm) continue;
    const Eigen::Vector3d& at = b[i].points_mm.back();
    notes.push_back(fmt::format(
        "a vessel stops at ({:.1f}, {:.1f}, {:.1f}) mm while {:.2f} mm in radius: an occlusion or a stenosis too tight "
        "to follow; the tree ends there",
        at.x(), at.y(), at.z(), r));
  }
  return notes;
}

}  // namespace pcisim::modeling
