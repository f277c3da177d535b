#pragma once
// The contact rules of the tissue solver, one function each, with the rule above it. The
// support and the probe are static or kinematic (infinite mass): every correction goes to the
// particle.
#include <Eigen/Core>
#include <algorithm>
#include <span>

#include "physics/soft_tissue/contact_plane.h"
#include "physics/soft_tissue/convex_probe.h"

namespace pcisim::physics::soft_tissue {

// gap of a particle (a sphere of radius r about x) to a plane, negative when it penetrates:
//   C(x) = n . x - d - r
inline double plane_gap_m(const Eigen::Vector3d& x_m, const ContactPlane& plane, double radius_m) {
  return plane.normal.dot(x_m) - plane.offset_m - radius_m;
}

// non-penetration, the inequality C(x) >= 0 [soft-tissue eq 2] projected by [soft-tissue eqs 4-5]
// with grad C = n and the other body's inverse mass 0: lambda = -C / w, dx = w lambda n, i.e.
// dx = -min(C, 0) n, all of it to the particle [soft-tissue, Algorithm 1 lines 12 and 19].
// Returns the normal correction's length, >= 0.
inline double non_penetration_m(const ContactPlane& plane, double radius_m, Eigen::Vector3d* x_m) {
  const double c = plane_gap_m(*x_m, plane, radius_m);
  if (!(c < 0.0)) return 0.0;
  *x_m -= c * plane.normal;
  return -c;
}

// Coulomb friction as a positional correction (the paper's "shape friction" [soft-tissue,
// Table 1], as in FleX: Macklin et al. 2014, the paper's ref [16]; the form of [guidewire eq
// 17-18] with separate static and kinetic coefficients):
// slip = the tangential relative displacement of the contact over the substep, dn = the
// normal correction it received. Static: |slip| <= mu_s dn, the slip is undone (dx = -slip);
// kinetic: otherwise, the slip is shortened by mu_k dn (dx = -slip min(1, mu_k dn / |slip|)).
inline Eigen::Vector3d coulomb_friction_m(const Eigen::Vector3d& slip_m, double normal_correction_m, double mu_static,
                                          double mu_kinetic) {
  const double len = slip_m.norm();
  if (!(len > 0.0)) return Eigen::Vector3d::Zero();
  if (len <= mu_static * normal_correction_m) return -slip_m;
  return -slip_m * std::min(1.0, mu_kinetic * normal_correction_m / len);
}

// the probe's face of least penetration [soft-tissue, "Collision and data preparation": the
// probe is a convex body, an intersection of half-spaces]: a point is pushed out through the face
// whose plane is nearest, i.e. the largest signed distance n_i . x - d_i (inside, all are <= 0);
// outside, the same face is the one that separates it best. Ties go to the lowest index. Returns
// the face index (-1 when there are no faces) and writes its signed distance.
int least_penetration_face(std::span<const HalfSpace> faces, const ProbePose& pose, const Eigen::Vector3d& x_m,
                           double* signed_distance_m);

}  // namespace pcisim::physics::soft_tissue
