#include "physics/heart/heart_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "anatomy/heart/heart_frame.h"
#include "anatomy/heart/template_heart_surface.h"

namespace pcisim::physics {
namespace {

double smoothstep01(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

// the designed epicardium's radius along a patient-frame direction (metres)
double surface_radius_m(const Eigen::Vector3d& patient_dir) {
  return 1e-3 * anatomy::epicardial_radius_mm(anatomy::heart_to_patient().transpose() * patient_dir);
}

// one sunken centerline point: its direction from the heart centre and how deep it sinks
struct Dent {
  Eigen::Vector3d dir;
  double depth_m;
};

}  // namespace

double clearance_above_epicardium_m(const anatomy::CenterlinePoint& point) {
  const double r = point.position_m.norm();
  if (!(r > 0.0)) return -std::numeric_limits<double>::infinity();
  return r - point.radius_m - surface_radius_m(point.position_m / r);
}

HeartFitReport fit_heart_under_tree(const anatomy::VesselTree& tree, const HeartFitParams& params,
                                    anatomy::HeartMesh* mesh) {
  HeartFitReport report;
  // the branches that sink deeper than the tolerance, every point of them below the surface
  std::vector<Dent> dents;
  for (const auto& branch : tree.branches) {
    if (branch.name == "aorta") continue;
    double deepest = 0.0;
    for (const auto& p : branch.points) deepest = std::min(deepest, clearance_above_epicardium_m(p));
    if (deepest >= -params.tolerance_m) continue;
    ++report.branches_lifted;
    for (const auto& p : branch.points) {
      const double c = clearance_above_epicardium_m(p);
      if (c < 0.0) dents.push_back({p.position_m.normalized(), -c});
    }
  }
  if (dents.empty()) return report;

  // each vertex moves toward the centre by the deepest dent near it: full within core_m of a
  // sunken point (along the surface), fading over fade_m, and fading over depth_m into the wall
  for (int v = 0; v < mesh->vertices_m.cols(); ++v) {
    const Eigen::Vector3d x = mesh->vertices_m.col(v);
    const double r = x.norm();
    if (!(r > 0.0)) continue;
    const Eigen::Vector3d u = x / r;
    const double r_surface = surface_radius_m(u);
    const double depth_weight = 1.0 - smoothstep01((r_surface - r) / params.depth_m);
    if (depth_weight <= 0.0) continue;
    double dent_m = 0.0;
    for (const Dent& d : dents) {
      const double along_m = r_surface * std::acos(std::clamp(u.dot(d.dir), -1.0, 1.0));
      const double w = 1.0 - smoothstep01((along_m - params.core_m) / params.fade_m);
      dent_m = std::max(dent_m, d.depth_m * w);
    }
    const double move_m = dent_m * depth_weight;
    if (move_m <= 0.0) continue;
    mesh->vertices_m.col(v) = x - move_m * u;
    ++report.vertices_moved;
    report.max_dent_m = std::max(report.max_dent_m, move_m);
  }
  return report;
}

}  // namespace pcisim::physics
