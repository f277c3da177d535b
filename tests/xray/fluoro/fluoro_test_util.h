#pragma once
// A small fluoroscopy setup for tests: the seed-1 coronary tree, a coarse phantom and a 256^2
// detector at 0.8 mm (the default 205 mm field), LAO 30 / CRA 20 at the heart centre.
#include "anatomy/phantom/coronary_phantom.h"
#include "xray/fluoro/fluoroscopy.h"

namespace pcisim::xray::testing {

inline FluoroSpec small_fluoro_spec() {
  FluoroSpec s;
  s.c_arm.width = s.c_arm.height = 256;
  s.c_arm.pixel_mm = 0.8;
  s.volume_dims = {96, 96, 48};
  s.volume_spacing_mm = 3.73;
  s.projector.trilinear.threads = 1;
  return s;
}

inline CArmPose lao30_cra20() {
  return CArmPose{30, 20, Eigen::Vector3d::Zero()};
}

}  // namespace pcisim::xray::testing
