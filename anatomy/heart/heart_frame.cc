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

}  // namespace pcisim::anatomy
