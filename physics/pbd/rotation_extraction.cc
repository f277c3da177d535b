#include "physics/pbd/rotation_extraction.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>

namespace pcisim::physics::pbd {

Eigen::Matrix3d extract_rotation(const Eigen::Matrix3d& a, const Eigen::Matrix3d& previous, double rest_moment_kg_m2) {
  // a cluster with no rest extent still needs a nonzero pull toward its previous frame
  const double scale = std::max(kRotationRegularisation * rest_moment_kg_m2, 1e-300);
  const Eigen::Matrix3d m = a + scale * previous;
  if (!m.allFinite()) return previous;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  const Eigen::Matrix3d& v = svd.matrixV();
  // singular values come sorted: flipping the last column reflects the thinnest direction only
  if ((u * v.transpose()).determinant() < 0.0) u.col(2) = -u.col(2);
  const Eigen::Matrix3d r = u * v.transpose();
  return r.allFinite() ? r : previous;
}

}  // namespace pcisim::physics::pbd
