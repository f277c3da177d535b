#pragma once
// The coronary phantom's heart frame (anatomy/phantom/coronary_phantom.cc): e1 anterior, e2 patient
// left, e3 toward the base; the apex is at -e3. Columns of heart_to_patient() are e1, e2, e3.
#include <Eigen/Core>
#include <vector>

namespace pcisim::anatomy {

Eigen::Matrix3d heart_to_patient();

// heart-frame height (m) of the atrioventricular plane: the coronary phantom's AV groove runs at
// polar angles 50-60 deg on the 50 mm sphere. Below it lie the ventricles, whose motion a motion
// sequence gives (heart paper section 4); above it the atria and the aortic root
constexpr double kAvPlaneZM = 0.030;

// the columns of rest_m (template frame, patient LPS, metres) below the AV plane: the ventricles
std::vector<int> ventricular_points(const Eigen::Matrix3Xd& rest_m);

}  // namespace pcisim::anatomy
