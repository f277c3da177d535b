#include "physics/soft_tissue/contact_rules.h"

#include <stdexcept>
#include <string>

namespace pcisim::physics::soft_tissue {

int least_penetration_face(std::span<const HalfSpace> faces, const ProbePose& pose, const Eigen::Vector3d& x_m,
                           double* signed_distance_m) {
  pbd::device::ContactFace world[pbd::device::kMaxContactFaces];
  if (faces.size() > static_cast<size_t>(pbd::device::kMaxContactFaces))
    throw std::invalid_argument("soft_tissue: a probe of " + std::to_string(faces.size()) + " faces; at most " +
                                std::to_string(pbd::device::kMaxContactFaces));
  const int count = static_cast<int>(faces.size());
  for (int i = 0; i < count; ++i) {
    const ContactPlane p = world_face(faces[i], pose);
    world[i] = {{p.normal.x(), p.normal.y(), p.normal.z()}, p.offset_m};
  }
  *signed_distance_m = 0.0;
  return pbd::device::least_penetration_face(world, count, {x_m.x(), x_m.y(), x_m.z()}, signed_distance_m);
}

}  // namespace pcisim::physics::soft_tissue
