#pragma once
// The contact rules of the tissue solver on Eigen types, for callers and tests outside the step:
// each forwards to its rule in pbd/device_contacts.h (where the rule is written, once, for the CPU
// and the CUDA solver). The support and the probe are static or kinematic (infinite mass).
#include <Eigen/Core>
#include <span>

#include "physics/pbd/device_contacts.h"
#include "physics/soft_tissue/contact_plane.h"
#include "physics/soft_tissue/convex_probe.h"

namespace pcisim::physics::soft_tissue {

// C(x) = n . x - d - r (device::plane_gap_m)
inline double plane_gap_m(const Eigen::Vector3d& x_m, const ContactPlane& plane, double radius_m) {
  return pbd::device::plane_gap_m({x_m.x(), x_m.y(), x_m.z()},
                                  {{plane.normal.x(), plane.normal.y(), plane.normal.z()}, plane.offset_m}, radius_m);
}

// dx = -min(C, 0) n (device::non_penetration_m); returns the correction's length
inline double non_penetration_m(const ContactPlane& plane, double radius_m, Eigen::Vector3d* x_m) {
  pbd::device::Vec3 x{x_m->x(), x_m->y(), x_m->z()};
  const double moved = pbd::device::non_penetration_m(
      {{plane.normal.x(), plane.normal.y(), plane.normal.z()}, plane.offset_m}, radius_m, &x);
  *x_m = Eigen::Vector3d(x.x, x.y, x.z);
  return moved;
}

// Coulomb friction as a positional correction (device::coulomb_friction_m)
inline Eigen::Vector3d coulomb_friction_m(const Eigen::Vector3d& slip_m, double normal_correction_m, double mu_static,
                                          double mu_kinetic) {
  const pbd::device::Vec3 f =
      pbd::device::coulomb_friction_m({slip_m.x(), slip_m.y(), slip_m.z()}, normal_correction_m, mu_static, mu_kinetic);
  return {f.x, f.y, f.z};
}

// the probe's face of least penetration at a pose (device::least_penetration_face on the faces
// in world coordinates); -1 when there are none. Throws std::invalid_argument past
// device::kMaxContactFaces faces
int least_penetration_face(std::span<const HalfSpace> faces, const ProbePose& pose, const Eigen::Vector3d& x_m,
                           double* signed_distance_m);

}  // namespace pcisim::physics::soft_tissue
