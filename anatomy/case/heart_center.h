#pragma once
// Where a case's heart is: what the C-arm centres on. A case in a scanner's coordinates (a
// patient's CTA) has its heart far from the origin, where the built-in phantom has it.
#include <Eigen/Core>
#include "anatomy/case/case.h"

namespace pcisim::anatomy {

// the landmark "heart centre" when the case names one, else the middle of the bounding box of its
// coronary centerlines (every branch but the aorta), else the origin; millimetres, LPS
Eigen::Vector3d heart_center_mm(const Case& c);

}  // namespace pcisim::anatomy
