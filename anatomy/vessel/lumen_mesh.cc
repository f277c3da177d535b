#include "anatomy/vessel/lumen_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace pcisim::anatomy {
namespace {

using Eigen::Vector3d;

struct Ring {
  Vector3d center_m;
  Vector3d u, v;  // in-plane frame, u x v = the axis direction
  double radius_m;
};

// a unit vector perpendicular to t
Vector3d any_perpendicular(const Vector3d& t) {
  const Vector3d a = std::abs(t.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
  return t.cross(a).normalized();
}

// ring vertices needed so the polygon sags at most max_chord_error_m inside a circle of radius_m
int segments_for(double radius_m, const LumenMeshSpec& spec) {
  int n = std::max(3, spec.segments);
  if (spec.max_chord_error_m > 0.0 && radius_m > spec.max_chord_error_m) {
    const double half_angle = std::acos(1.0 - spec.max_chord_error_m / radius_m);
    n = std::max(n, static_cast<int>(std::ceil(std::numbers::pi / half_angle)));
  }
  return n;
}

// latitude rings per hemispherical cap. A cap facet sags along both its sides, so the latitude
// step gets half the bound: the facet's sag stays within ~1.5x the bound, the tube's within 1x
int cap_rings_for(double radius_m, const LumenMeshSpec& spec) {
  int n = std::max(1, spec.cap_rings);
  const double bound_m = 0.5 * spec.max_chord_error_m;
  if (bound_m > 0.0 && radius_m > bound_m) {
    const double step = 2.0 * std::acos(1.0 - bound_m / radius_m);
    n = std::max(n, static_cast<int>(std::ceil(std::numbers::pi / 2 / step)));
  }
  return n;
}

}  // namespace

void branch_sweep_points(const VesselTree& tree, const VesselBranch& branch, bool extend_to_parent,
                         std::vector<Vector3d>* points_m, std::vector<double>* radii_m) {
  std::vector<Vector3d>& pts = *points_m;
  std::vector<double>& radii = *radii_m;
  pts.clear();
  radii.clear();
  if (extend_to_parent && branch.parent >= 0 && branch.parent_point >= 0 && !branch.points.empty() &&
      branch.parent < static_cast<int>(tree.branches.size())) {
    const auto& pp = tree.branches[branch.parent].points;
    if (branch.parent_point < static_cast<int>(pp.size())) {
      const Vector3d to_parent = pp[branch.parent_point].position_m - branch.points[0].position_m;
      const double gap_m = to_parent.norm();
      if (gap_m > 1e-9) {
        pts.push_back(branch.points[0].position_m +
                      to_parent / gap_m * std::min(gap_m, pp[branch.parent_point].radius_m));
        radii.push_back(branch.points[0].radius_m);
      }
    }
  }
  for (const auto& p : branch.points) {
    if (!pts.empty() && (p.position_m - pts.back()).norm() < 1e-9) continue;
    pts.push_back(p.position_m);
    radii.push_back(p.radius_m);
  }
}

namespace {

TriangleMesh loft_branch(const VesselTree& tree, const VesselBranch& branch, const LumenMeshSpec& spec) {
  TriangleMesh mesh;
  std::vector<Vector3d> pts;
  std::vector<double> radii;
  branch_sweep_points(tree, branch, true, &pts, &radii);
  if (pts.size() < 2) return mesh;
  const size_t n = pts.size();

  std::vector<Vector3d> tangent(n);
  for (size_t i = 0; i < n; ++i) {
    const Vector3d d = pts[std::min(i + 1, n - 1)] - pts[i == 0 ? 0 : i - 1];
    tangent[i] = d.norm() > 0 ? d.normalized() : (i > 0 ? tangent[i - 1] : Vector3d::UnitX());
  }
  // rotation-minimising frames by double reflection (Wang et al. 2008): no twist along the tube
  std::vector<Ring> body(n);
  Vector3d r = any_perpendicular(tangent[0]);
  double r_max_m = 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (i > 0) {
      const Vector3d v1 = pts[i] - pts[i - 1];
      const double c1 = v1.squaredNorm();
      Vector3d r_l = r, t_l = tangent[i - 1];
      if (c1 > 0) {
        r_l = r - (2.0 / c1) * v1.dot(r) * v1;
        t_l = tangent[i - 1] - (2.0 / c1) * v1.dot(tangent[i - 1]) * v1;
      }
      const Vector3d v2 = tangent[i] - t_l;
      const double c2 = v2.squaredNorm();
      r = c2 > 1e-30 ? Vector3d(r_l - (2.0 / c2) * v2.dot(r_l) * v2) : r_l;
    }
    Vector3d u = r - tangent[i] * tangent[i].dot(r);
    u = u.norm() > 1e-12 ? u.normalized() : any_perpendicular(tangent[i]);
    r = u;
    body[i] = {pts[i], u, tangent[i].cross(u), radii[i]};
    r_max_m = std::max(r_max_m, radii[i]);
  }
  const int segs = segments_for(r_max_m, spec);

  // hemispherical caps: latitude rings from the start pole to the equator, and back at the end
  const int k_cap = cap_rings_for(r_max_m, spec);
  const double quarter = std::numbers::pi / 2;
  std::vector<Ring> rings;
  rings.reserve(n + 2 * k_cap);
  const Ring& first = body.front();
  const Vector3d t0 = first.u.cross(first.v);
  for (int k = k_cap - 1; k >= 1; --k) {
    const double a = quarter * k / k_cap;
    rings.push_back(
        {first.center_m - first.radius_m * std::sin(a) * t0, first.u, first.v, first.radius_m * std::cos(a)});
  }
  rings.insert(rings.end(), body.begin(), body.end());
  const Ring& last = body.back();
  const Vector3d t1 = last.u.cross(last.v);
  for (int k = 1; k < k_cap; ++k) {
    const double a = quarter * k / k_cap;
    rings.push_back({last.center_m + last.radius_m * std::sin(a) * t1, last.u, last.v, last.radius_m * std::cos(a)});
  }

  mesh.vertices_m.reserve(rings.size() * segs + 2);
  for (const Ring& ring : rings) {
    for (int j = 0; j < segs; ++j) {
      const double a = 2.0 * std::numbers::pi * j / segs;
      mesh.vertices_m.push_back(ring.center_m + ring.radius_m * (std::cos(a) * ring.u + std::sin(a) * ring.v));
    }
  }
  const int start_pole = static_cast<int>(mesh.vertices_m.size());
  mesh.vertices_m.push_back(first.center_m - first.radius_m * t0);
  const int end_pole = start_pole + 1;
  mesh.vertices_m.push_back(last.center_m + last.radius_m * t1);

  // (ring i, j) -> (i, j+1) runs counter-clockwise about the axis, so these windings face out
  auto at = [segs](int i, int j) { return i * segs + (j % segs); };
  const int ring_count = static_cast<int>(rings.size());
  mesh.triangles.reserve(2 * segs * ring_count);
  for (int j = 0; j < segs; ++j) mesh.triangles.push_back({start_pole, at(0, j + 1), at(0, j)});
  for (int i = 0; i + 1 < ring_count; ++i) {
    for (int j = 0; j < segs; ++j) {
      mesh.triangles.push_back({at(i, j), at(i, j + 1), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i + 1, j)});
    }
  }
  for (int j = 0; j < segs; ++j) mesh.triangles.push_back({at(ring_count - 1, j), at(ring_count - 1, j + 1), end_pole});
  return mesh;
}

}  // namespace

std::vector<TriangleMesh> loft_branch_tubes(const VesselTree& tree, const LumenMeshSpec& spec) {
  std::vector<TriangleMesh> tubes(tree.branches.size());
  for (size_t i = 0; i < tree.branches.size(); ++i) {
    const auto& b = tree.branches[i];
    if (std::find(spec.exclude.begin(), spec.exclude.end(), b.name) != spec.exclude.end()) continue;
    tubes[i] = loft_branch(tree, b, spec);
  }
  return tubes;
}

void append_mesh(TriangleMesh& a, const TriangleMesh& b) {
  const int offset = static_cast<int>(a.vertices_m.size());
  a.vertices_m.insert(a.vertices_m.end(), b.vertices_m.begin(), b.vertices_m.end());
  a.triangles.reserve(a.triangles.size() + b.triangles.size());
  for (const auto& t : b.triangles) a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
}

TriangleMesh loft_lumen(const VesselTree& tree, const LumenMeshSpec& spec) {
  TriangleMesh lumen;
  for (const TriangleMesh& tube : loft_branch_tubes(tree, spec)) append_mesh(lumen, tube);
  return lumen;
}

}  // namespace pcisim::anatomy
