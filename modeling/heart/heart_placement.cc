#include "modeling/heart/heart_placement.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <stdexcept>
#include <vector>

#include "anatomy/phantom/coronary_phantom.h"
#include "realtime/percentile.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

// the aortic root's first `root_mm` and every other branch, every `step_mm` of arc length (mm)
std::vector<Vector3d> sample_tree(const anatomy::VesselTree& tree, double step_mm, double root_mm) {
  std::vector<Vector3d> out;
  for (const auto& b : tree.branches) {
    const bool aorta = b.name == "aorta";
    double s = 0, next = 0;
    for (size_t i = 0; i < b.points.size(); ++i) {
      if (i > 0) s += (b.points[i].position_m - b.points[i - 1].position_m).norm() * 1e3;
      if (aorta && s > root_mm) break;
      if (s + 1e-9 >= next) {
        out.push_back(b.points[i].position_m * 1e3);
        next += step_mm;
      }
    }
  }
  return out;
}

Vector3d first_point(const anatomy::VesselTree& t, const char* name, bool* found) {
  const int i = t.find(name);
  *found = i >= 0 && !t.branches[i].points.empty();
  return *found ? Vector3d(t.branches[i].points.front().position_m * 1e3) : Vector3d::Zero();
}

}  // namespace

HeartPlacement place_template_heart(const anatomy::VesselTree& patient, const HeartPlacementOptions& o) {
  // the template's tree: the one its heart was built around (dense, 0.5 mm), mm
  const anatomy::VesselTree tmpl_tree = anatomy::make_coronary_phantom({.seed = 1});
  const std::vector<Vector3d> tmpl = sample_tree(tmpl_tree, 0.5, o.aorta_root_mm);
  const std::vector<Vector3d> pts = sample_tree(patient, o.sample_spacing_mm, o.aorta_root_mm);
  if (pts.size() < 10) {
    throw std::invalid_argument("heart placement: the vessel tree has fewer than 10 points to place the heart under");
  }
  // start: the ostia on each other (their midpoint), else the centroids
  bool a1, a2, b1, b2;
  const Vector3d pl = first_point(patient, "LM", &a1), pr = first_point(patient, "RCA", &a2);
  const Vector3d tl = first_point(tmpl_tree, "LM", &b1), tr = first_point(tmpl_tree, "RCA", &b2);
  Vector3d shift;
  if (a1 && a2 && b1 && b2) {
    shift = 0.5 * (pl + pr) - 0.5 * (tl + tr);
  } else {
    Vector3d cp = Vector3d::Zero(), ct = Vector3d::Zero();
    for (const auto& p : pts) cp += p;
    for (const auto& p : tmpl) ct += p;
    shift = cp / double(pts.size()) - ct / double(tmpl.size());
  }
  Eigen::Matrix3d rot = Eigen::Matrix3d::Identity();
  double scale = 1.0;
  Vector3d trans = shift;  // patient = scale rot tmpl + trans (mm)

  HeartPlacement out;
  std::vector<double> d2(pts.size());
  std::vector<int> match(pts.size());
  for (int it = 0; it < o.iterations; ++it) {
    // each patient point's closest template point, under the current pose (brute force: a few
    // hundred by a few thousand points)
    const Eigen::Matrix3d to_t = rot.transpose() / scale;
    for (size_t i = 0; i < pts.size(); ++i) {
      const Vector3d q = to_t * (pts[i] - trans);
      double best = 1e300;
      for (size_t j = 0; j < tmpl.size(); ++j) {
        const double d = (tmpl[j] - q).squaredNorm();
        if (d < best) {
          best = d;
          match[i] = static_cast<int>(j);
        }
      }
      d2[i] = best * scale * scale;
    }
    std::vector<double> sorted = d2;
    const double cut =
        o.trim_factor * o.trim_factor * std::max(realtime::upper_median_in_place(std::span<double>(sorted)), 0.25);
    Eigen::Matrix3Xd src(3, pts.size()), dst(3, pts.size());
    int n = 0;
    double sum = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      if (d2[i] > cut) continue;
      src.col(n) = tmpl[match[i]];
      dst.col(n) = pts[i];
      sum += d2[i];
      ++n;
    }
    if (n < 10) break;
    const Eigen::Matrix4d t = Eigen::umeyama(src.leftCols(n), dst.leftCols(n), true);
    const double s = std::cbrt(t.topLeftCorner<3, 3>().determinant());
    rot = t.topLeftCorner<3, 3>() / s;
    scale = std::clamp(s, o.min_scale, o.max_scale);
    trans = t.topRightCorner<3, 1>();
    out.rms_mm = std::sqrt(sum / n);
    out.pairs = n;
    out.iterations_run = it + 1;
  }
  out.pose.rotation = rot;
  out.pose.scale = scale;
  out.pose.translation_m = trans * 1e-3;  // the template's frame is metres, as the case's
  return out;
}

}  // namespace pcisim::modeling
