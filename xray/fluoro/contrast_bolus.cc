#include "xray/fluoro/contrast_bolus.h"

#include <algorithm>
#include <cmath>

namespace pcisim::xray {
namespace {

// distance from p to the polyline through points [lo, hi] of branch, and the radius there
bool inside_lumen(const anatomy::VesselBranch& branch, int lo, int hi, const Eigen::Vector3d& p_m) {
  const auto& pts = branch.points;
  lo = std::max(lo, 0);
  hi = std::min<int>(hi, static_cast<int>(pts.size()) - 1);
  for (int i = lo; i < hi; ++i) {
    const Eigen::Vector3d a = pts[i].position_m, ab = pts[i + 1].position_m - a;
    const double u = std::clamp((p_m - a).dot(ab) / std::max(ab.squaredNorm(), 1e-18), 0.0, 1.0);
    const double r = pts[i].radius_m + u * (pts[i + 1].radius_m - pts[i].radius_m);
    if ((p_m - a - u * ab).squaredNorm() < r * r) return true;
  }
  return false;
}

}  // namespace

ContrastBolus::ContrastBolus(const anatomy::VesselTree& tree, const ContrastBolusSpec& spec) : spec_(spec) {
  const int n = static_cast<int>(tree.branches.size());
  const int aorta = tree.find("aorta");
  branch_names_.reserve(n);
  for (const auto& b : tree.branches) branch_names_.push_back(b.name);
  // distance of each centerline point below the ostium; parents first (recursion by index)
  std::vector<std::vector<double>> s_mm(n);
  std::vector<int> first_kept(n, 0);
  std::vector<CoronaryOstium> ostium(n, CoronaryOstium::kLeft);
  std::vector<int> state(n, 0);  // 0 todo, 1 busy, 2 done
  auto solve = [&](auto&& self, int b) -> void {
    if (state[b] != 0) return;
    state[b] = 1;
    const auto& br = tree.branches[b];
    const int parent = br.parent;
    const bool root = parent < 0 || parent == aorta;
    double s0 = 0;
    if (!root && parent < n && state[parent] != 1) {
      self(self, parent);
      ostium[b] = ostium[parent];
      const auto& ps = s_mm[parent];
      if (!ps.empty()) s0 = ps[std::clamp<int>(br.parent_point, 0, static_cast<int>(ps.size()) - 1)];
    } else {
      ostium[b] = br.name == "RCA" ? CoronaryOstium::kRight : CoronaryOstium::kLeft;
    }
    // skip the points inside the parent's lumen (near the junction)
    int k = 0;
    if (parent >= 0 && parent < n) {
      const int pp = br.parent_point;
      while (k < static_cast<int>(br.points.size()) &&
             inside_lumen(tree.branches[parent], pp - 40, pp + 40, br.points[k].position_m)) {
        ++k;
      }
    }
    first_kept[b] = k;
    auto& s = s_mm[b];
    s.assign(br.points.size(), 0.0);
    double acc = root ? 0.0 : s0;
    for (size_t i = 0; i < br.points.size(); ++i) {
      if (i > 0) acc += 1000.0 * (br.points[i].position_m - br.points[i - 1].position_m).norm();
      s[i] = acc;
    }
    if (root) {  // the ostium is where the lumen leaves the aorta
      const double exit = k < static_cast<int>(s.size()) ? s[k] : 0.0;
      for (double& v : s) v = std::max(0.0, v - exit);
    }
    state[b] = 2;
  };
  for (int b = 0; b < n; ++b) {
    if (b != aorta) solve(solve, b);
  }
  std::vector<int> first_point(n, 0);
  for (int b = 0; b < n; ++b) {
    first_point[b] = tree_point_count_;
    tree_point_count_ += static_cast<int>(tree.branches[b].points.size());
  }
  for (int b = 0; b < n; ++b) {
    if (b == aorta) continue;
    const auto& pts = tree.branches[b].points;
    int i = first_kept[b];
    while (i + 1 < static_cast<int>(pts.size())) {
      // the next point at least segment_mm away (or the last one)
      int j = i + 1;
      while (j + 1 < static_cast<int>(pts.size()) && s_mm[b][j] - s_mm[b][i] < spec_.segment_mm) ++j;
      LumenSegment seg;
      seg.a_mm = 1000.0 * pts[i].position_m;
      seg.b_mm = 1000.0 * pts[j].position_m;
      seg.ra_mm = 1000.0 * pts[i].radius_m;
      seg.rb_mm = 1000.0 * pts[j].radius_m;
      seg.s_mm = 0.5 * (s_mm[b][i] + s_mm[b][j]);
      seg.branch = b;
      seg.point_a = first_point[b] + i;
      seg.point_b = first_point[b] + j;
      seg.ostium = ostium[b];
      segments_.push_back(seg);
      i = j;
    }
  }
  segment_opacity_.assign(segments_.size(), 0.0);
  branch_opacity_.assign(n, 0.0);
}

double ContrastBolus::opacity(double s_mm, CoronaryOstium ostium, double t_s,
                              std::span<const ContrastInjection> injections) const {
  double c = 0;
  if (!std::isfinite(t_s) || !std::isfinite(s_mm)) return 0.0;
  for (const ContrastInjection& inj : injections) {
    if (!std::isfinite(inj.start_s) || !std::isfinite(inj.duration_s) || !std::isfinite(inj.volume_ml)) continue;
    if (inj.ostium != ostium || !(inj.duration_s > 0) || !(inj.volume_ml > 0)) continue;
    const double flow = ostium == CoronaryOstium::kLeft ? spec_.left_flow_ml_per_s : spec_.right_flow_ml_per_s;
    const double peak = std::min(1.0, inj.volume_ml / inj.duration_s / flow);
    // time since the front reached this point
    const double tau = t_s - inj.start_s - s_mm / spec_.velocity_mm_per_s;
    if (tau <= 0) continue;
    const double filled = 1.0 - std::exp(-std::min(tau, inj.duration_s) / spec_.rise_s);
    const double washed = tau > inj.duration_s ? std::exp(-(tau - inj.duration_s) / spec_.washout_s) : 1.0;
    c += peak * filled * washed;
  }
  return std::min(1.0, c) * std::exp(-s_mm / spec_.taper_mm);
}

void ContrastBolus::move(std::span<const Eigen::Vector3d> points_m) {
  if (static_cast<int>(points_m.size()) != tree_point_count_) return;
  for (LumenSegment& seg : segments_) {
    seg.a_mm = 1000.0 * points_m[seg.point_a];
    seg.b_mm = 1000.0 * points_m[seg.point_b];
  }
}

void ContrastBolus::update(double t_s, std::span<const ContrastInjection> injections) {
  std::fill(branch_opacity_.begin(), branch_opacity_.end(), 0.0);
  for (size_t i = 0; i < segments_.size(); ++i) {
    const LumenSegment& seg = segments_[i];
    const double o = opacity(seg.s_mm, seg.ostium, t_s, injections);
    segment_opacity_[i] = o;
    branch_opacity_[seg.branch] = std::max(branch_opacity_[seg.branch], o);
  }
}

}  // namespace pcisim::xray
