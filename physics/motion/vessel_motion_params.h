#pragma once
// What a scene sets for effect `vessel_motion`: how the coronary tree is tied to the beating
// heart's epicardium.
#include "physics/param_checks.h"

namespace pcisim::physics {

struct VesselMotionParams {
  // tree points within this distance of the epicardium ride it fully (the coronaries lie on it
  // with their radius, ~1-2 mm, plus fat)
  double attach_distance_m = 0.006;
  // beyond it the ride fades linearly to nothing over this distance: the aortic root, where the
  // guide catheter sits, stays put
  double fade_distance_m = 0.010;
  // radius of the blend that carries points between centerline samples (the wire inside the
  // lumen): samples within it weigh in by inverse squared distance
  double blend_radius_m = 0.004;
};

// each field's range, one source for VesselSkin's validation and the scene loader
inline constexpr ParamRange kMotionAttachDistanceM{0, 0.05};
inline constexpr ParamRange kMotionFadeDistanceM{0, 0.1};
inline constexpr ParamRange kMotionBlendRadiusM{1e-3, 0.02};

}  // namespace pcisim::physics
