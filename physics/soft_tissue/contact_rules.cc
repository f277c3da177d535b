#include "physics/soft_tissue/contact_rules.h"

namespace pcisim::physics::soft_tissue {

int least_penetration_face(std::span<const HalfSpace> faces, const ProbePose& pose, const Eigen::Vector3d& x_m,
                           double* signed_distance_m) {
  const Eigen::Vector3d local = pose.rotation.conjugate() * (x_m - pose.position_m);
  int best = -1;
  double best_d = 0.0;
  for (int i = 0; i < static_cast<int>(faces.size()); ++i) {
    const double d = faces[i].normal.dot(local) - faces[i].offset_m;
    if (best < 0 || d > best_d) best = i, best_d = d;  // strict: a tie keeps the first face
  }
  *signed_distance_m = best_d;
  return best;
}

}  // namespace pcisim::physics::soft_tissue
