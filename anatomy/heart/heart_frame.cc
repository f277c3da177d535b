#include "anatomy/heart/heart_frame.h"

#include <Eigen/Geometry>

namespace pcisim::anatomy {

Eigen::Matrix3d heart_to_patient() {
  // the same base direction and anterior as make_coronary_phantom
  const Eigen::Vector3d base = Eigen::Vector3d(-0.45, 0.35, 0.82).normalized();
  const Eigen::Vector3d back(0, -1, 0);
  const Eigen::Vector3d anterior = (back - base * base.dot(back)).normalized();
  Eigen::Matrix3d m;
  m.col(0) = anterior;
  m.col(1) = base.cross(anterior);
  m.col(2) = base;
  return m;
}

std::vector<int> ventricular_points(const Eigen::Matrix3Xd& rest_m) {
  const Eigen::Matrix3d to_heart = heart_to_patient().transpose();
  std::vector<int> out;
  for (Eigen::Index i = 0; i < rest_m.cols(); ++i)
    if ((to_heart * rest_m.col(i)).z() < kAvPlaneZM) out.push_back(static_cast<int>(i));
  return out;
}

}  // namespace pcisim::anatomy
