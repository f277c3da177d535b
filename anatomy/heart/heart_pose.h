#pragma once
// Where the template heart sits in a case: a similarity (rotation, uniform scale, translation)
// from the template's frame (docs/heart.md: heart centre at the origin, LPS, metres) to the case's.
// The built-in phantom's heart is the template itself (identity); a patient's model places it
// under the patient's coronary tree (modeling/heart/heart_placement.h).
#include <Eigen/Core>

namespace pcisim::anatomy {

struct HeartPose {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // proper rotation
  double scale = 1.0;
  Eigen::Vector3d translation_m = Eigen::Vector3d::Zero();

  Eigen::Vector3d to_case(const Eigen::Vector3d& template_m) const {
    return scale * (rotation * template_m) + translation_m;
  }
  Eigen::Vector3d to_template(const Eigen::Vector3d& case_m) const {
    return rotation.transpose() * (case_m - translation_m) / scale;
  }
  bool is_identity() const { return rotation == Eigen::Matrix3d::Identity() && scale == 1.0 && translation_m.isZero(); }
};

}  // namespace pcisim::anatomy
