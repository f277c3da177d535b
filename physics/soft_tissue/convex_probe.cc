#include "physics/soft_tissue/convex_probe.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace pcisim::physics::soft_tissue {

ConvexProbe box_probe(const Eigen::Vector3d& half_extent_m, const ProbePose& pose) {
  if (!half_extent_m.allFinite() || !(half_extent_m.minCoeff() > 0.0))
    throw std::invalid_argument("box_probe: half_extent_m must be finite and positive");
  ConvexProbe probe;
  probe.pose = pose;
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {1.0, -1.0}) probe.faces.push_back({sign * Eigen::Vector3d::Unit(axis), half_extent_m[axis]});
  return probe;
}

ConvexProbe normalised(const ConvexProbe& probe) {
  ConvexProbe out = probe;
  for (size_t i = 0; i < out.faces.size(); ++i) {
    HalfSpace& f = out.faces[i];
    const double len = f.normal.norm();
    if (!f.normal.allFinite() || !(len > 0.0) || !std::isfinite(len) || !std::isfinite(f.offset_m))
      throw std::invalid_argument("probe: face " + std::to_string(i) +
                                  " needs a finite non-zero normal and a finite offset_m");
    // n.x <= d is the same half-space as (n/|n|).x <= d/|n|
    f.normal /= len;
    f.offset_m /= len;
  }
  if (!out.pose.position_m.allFinite() || !out.pose.rotation.coeffs().allFinite() || !(out.pose.rotation.norm() > 0.0))
    throw std::invalid_argument("probe: the pose must be finite with a non-zero quaternion");
  out.pose.rotation.normalize();
  return out;
}

ProbePose interpolate(const ProbePose& a, const ProbePose& b, double t) {
  return {a.position_m + t * (b.position_m - a.position_m), a.rotation.slerp(t, b.rotation)};
}

// n_w = R n, and n.x_local <= d with x_local = R^T (x - p) is n_w.x <= d + n_w.p
ContactPlane world_face(const HalfSpace& face, const ProbePose& pose) {
  const Eigen::Vector3d n = pose.rotation * face.normal;
  return {n, face.offset_m + n.dot(pose.position_m)};
}

}  // namespace pcisim::physics::soft_tissue
