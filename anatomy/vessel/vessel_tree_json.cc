#include "anatomy/vessel/vessel_tree_json.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "anatomy/case/case_limits.h"
#include "anatomy/volume/io_text.h"
#include "json/json_reader.h"

namespace pcisim::anatomy {
namespace {

using nlohmann::json;
using namespace case_limits;

// every error names the file and the JSON path of the offending field
[[noreturn]] void fail(const std::string& file, const std::string& path, const std::string& what) {
  throw std::runtime_error(file + ": " + path + ": " + what);
}

void reject_unknown_keys(const json& object, std::initializer_list<const char*> known, const std::string& file,
                         const std::string& path) {
  for (auto it = object.begin(); it != object.end(); ++it) {
    bool ok = false;
    for (const char* k : known) ok = ok || it.key() == k;
    if (!ok) fail(file, path + "." + it.key(), "unknown key");
  }
}

// a pointer, not a reference: gcc 13 takes a reference returned next to temporary arguments
// for a dangling one
const json* member(const json& object, const char* key, const std::string& file, const std::string& path) {
  const auto it = object.find(key);
  if (it == object.end()) fail(file, path + "." + key, "missing");
  return &*it;
}

double finite_number(const json& v, const std::string& file, const std::string& path) {
  if (!v.is_number()) fail(file, path, "expected a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail(file, path, "expected a finite number");
  return x;
}

int integer_in(const json& v, int lo, int hi, const std::string& file, const std::string& path) {
  if (!v.is_number_integer()) {
    fail(file, path, "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  const auto x = v.get<long long>();
  if (x < lo || x > hi) {
    fail(file, path,
         "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + std::to_string(x));
  }
  return static_cast<int>(x);
}

}  // namespace

void write_vessel_tree_json(const VesselTree& tree, const std::string& path) {
  json branches = json::array();
  for (const auto& b : tree.branches) {
    json points = json::array();
    for (const auto& p : b.points) {
      points.push_back(
          {{"position_m", {p.position_m.x(), p.position_m.y(), p.position_m.z()}}, {"radius_m", p.radius_m}});
    }
    branches.push_back(
        {{"name", b.name}, {"parent", b.parent}, {"parent_point", b.parent_point}, {"points", std::move(points)}});
  }
  const json doc = {{"format", "pcisim-vessel-tree"}, {"version", 1}, {"branches", std::move(branches)}};
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  // nlohmann writes doubles with max_digits10, so a read gives back the same bits
  out << doc.dump(1) << '\n';
  out.flush();
  if (!out) throw std::runtime_error(path + ": write failed");
}

VesselTree read_vessel_tree_json(const std::string& file) {
  // the shared reader: a regular file only (a FIFO would block for ever), refused over the limit
  // unread; parsed at most kMaxJsonDepth deep (a deep file overflowed the stack), no key twice
  // (both throw runtime_errors naming the file: unreadable; syntax, or a number out of range)
  const json doc = pcisim::json::parse_json_checked(io::read_file(file, kMaxVesselTreeFileBytes), file);
  if (!doc.is_object()) fail(file, "(root)", "expected an object");
  reject_unknown_keys(doc, {"format", "version", "branches"}, file, "(root)");
  const json& format = *member(doc, "format", file, "(root)");
  if (format != "pcisim-vessel-tree") fail(file, "format", "expected \"pcisim-vessel-tree\"");
  integer_in(*member(doc, "version", file, "(root)"), 1, 1, file, "version");
  const json& branches = *member(doc, "branches", file, "(root)");
  if (!branches.is_array() || branches.empty()) fail(file, "branches", "expected a non-empty array");
  // every count and length is bounded before the points are read: the lofted tubes and the
  // wall-contact field grow with them (docs/anatomy.md, "Limits")
  if (branches.size() > static_cast<size_t>(kMaxBranches))
    fail(file, "branches", fmt::format("{} branches, more than {} (the limit)", branches.size(), kMaxBranches));

  VesselTree tree;
  size_t tree_points = 0;
  double tree_length_m = 0.0;
  tree.branches.reserve(branches.size());
  for (size_t i = 0; i < branches.size(); ++i) {
    const std::string bp = "branches[" + std::to_string(i) + "]";
    const json& jb = branches[i];
    if (!jb.is_object()) fail(file, bp, "expected an object");
    reject_unknown_keys(jb, {"name", "parent", "parent_point", "points"}, file, bp);
    VesselBranch b;
    const json& name = *member(jb, "name", file, bp);
    if (!name.is_string() || name.get<std::string>().empty()) {
      fail(file, bp + ".name", "expected a non-empty string");
    }
    b.name = name.get<std::string>();
    if (tree.find(b.name) >= 0) fail(file, bp + ".name", "duplicate branch name \"" + b.name + "\"");
    // parents come first in the list, which also rules out cycles
    b.parent = integer_in(*member(jb, "parent", file, bp), -1, static_cast<int>(i) - 1, file, bp + ".parent");
    const int parent_points = b.parent >= 0 ? static_cast<int>(tree.branches[b.parent].points.size()) : 0;
    if (b.parent >= 0) {
      b.parent_point =
          integer_in(*member(jb, "parent_point", file, bp), 0, parent_points - 1, file, bp + ".parent_point");
    } else {
      b.parent_point = -1;
      if (jb.contains("parent_point")) integer_in(jb["parent_point"], -1, -1, file, bp + ".parent_point");
    }
    const json& points = *member(jb, "points", file, bp);
    if (!points.is_array() || points.size() < 2) fail(file, bp + ".points", "expected an array of at least 2 points");
    if (points.size() > static_cast<size_t>(kMaxBranchPoints))
      fail(file, bp + ".points",
           fmt::format("{} points, more than {} (the limit per branch)", points.size(), kMaxBranchPoints));
    tree_points += points.size();
    if (tree_points > static_cast<size_t>(kMaxTreePoints))
      fail(file, bp + ".points",
           fmt::format("the tree reaches {} points here, more than {} (the limit for the tree)", tree_points,
                       kMaxTreePoints));
    b.points.reserve(points.size());
    for (size_t k = 0; k < points.size(); ++k) {
      const std::string pp = bp + ".points[" + std::to_string(k) + "]";
      const json& jp = points[k];
      if (!jp.is_object()) fail(file, pp, "expected an object");
      reject_unknown_keys(jp, {"position_m", "radius_m"}, file, pp);
      const json& pos = *member(jp, "position_m", file, pp);
      if (!pos.is_array() || pos.size() != 3) fail(file, pp + ".position_m", "expected an array of 3 numbers");
      CenterlinePoint c;
      for (int d = 0; d < 3; ++d) {
        const std::string cp = pp + ".position_m[" + std::to_string(d) + "]";
        c.position_m[d] = finite_number(pos[d], file, cp);
        if (std::abs(c.position_m[d]) > kMaxCoordinateM)
          fail(file, cp,
               fmt::format("{} m, more than {} m from the origin (the limit)", c.position_m[d], kMaxCoordinateM));
      }
      const json& r = *member(jp, "radius_m", file, pp);
      if (!r.is_number() || !std::isfinite(r.get<double>()) || r.get<double>() <= 0.0) {
        fail(file, pp + ".radius_m", "expected a number > 0");
      }
      c.radius_m = r.get<double>();
      if (c.radius_m < kMinVesselRadiusM || c.radius_m > kMaxVesselRadiusM)
        fail(file, pp + ".radius_m",
             fmt::format("{} m, outside [{}, {}] m (from a 99% stenosis to an aneurysmal aortic root)", c.radius_m,
                         kMinVesselRadiusM, kMaxVesselRadiusM));
      if (k > 0) {
        // a repeated point gives the tube no direction; a branch that doubles back on itself
        // over and over makes the length, and so the work, grow
        const double step_m = (c.position_m - b.points.back().position_m).norm();
        if (!(step_m >= kMinPointSpacingM))
          fail(file, pp + ".position_m",
               fmt::format("{:.3g} m from points[{}], closer than {} m (consecutive points must differ)", step_m, k - 1,
                           kMinPointSpacingM));
        tree_length_m += step_m;
        if (tree_length_m > kMaxTreeLengthM)
          fail(file, pp + ".position_m",
               fmt::format("the centerlines' total length passes {} m here (the limit for the tree)", kMaxTreeLengthM));
      }
      b.points.push_back(c);
    }
    tree.branches.push_back(std::move(b));
  }
  return tree;
}

}  // namespace pcisim::anatomy
