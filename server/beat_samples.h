#pragma once
// One cardiac cycle as the x-ray background needs it: physics samples the heart and the coronary
// centerline at each phase bin (metres, the case's frame), xray warps the CT with them (mm, the
// same frame: the CT's physical frame is the physics frame scaled by 1000).
#include "physics/world.h"
#include "server/scene/scene.h"
#include "xray/fluoro/beating_background.h"
#include "xray/fluoro/heart_warp.h"

namespace pcisim::server {

xray::BeatSamples beat_samples_mm(const physics::BeatCycle& cycle);

// how a scene's beating background is built: its blend choice and projector; on the GPU (the
// scene's projector "cuda") the changes too, at full resolution (well under a ms a bin)
xray::BeatingBackgroundOptions beat_options(const XraySpec& spec);

}  // namespace pcisim::server
