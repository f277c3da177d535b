#pragma once
// The coronary phantom's heart frame (anatomy/phantom/coronary_phantom.cc): e1 anterior, e2 patient
// left, e3 toward the base; the apex is at -e3. Columns of heart_to_patient() are e1, e2, e3.
#include <Eigen/Core>

namespace pcisim::anatomy {

Eigen::Matrix3d heart_to_patient();

}  // namespace pcisim::anatomy
