#pragma once
// What a scene asks physics to build. An effect is present exactly when its optional is set:
// an effect the scene does not list is never constructed.
#include <cstdint>
#include <optional>

#include "physics/guidewire/guidewire_params.h"
#include "physics/heart/heart_params.h"
#include "physics/motion/vessel_motion_params.h"
#include "physics/soft_tissue/soft_tissue_spec.h"

namespace pcisim::physics {

struct AnatomySpec {
  uint32_t seed = 1;  // procedural coronary phantom seed
};

struct WorldSpec {
  double step_s = 1.0 / 30.0;  // fixed physics step
  AnatomySpec anatomy;
  std::optional<GuidewireParams> guidewire;
  std::optional<VesselContactParams> vessel_contact;  // needs guidewire
  std::optional<FrictionParams> friction;             // needs vessel_contact
  std::optional<BloodFlowParams> blood_flow;          // needs guidewire; pulsatile with heart_beat
  std::optional<HeartBeatParams> heart_beat;          // the beating heart (stands alone)
  std::optional<VesselMotionParams> vessel_motion;    // the tree rides the heart: needs heart_beat
  // the soft-tissue scene: the case's organ as clustered shape-matching PBD on its support, and
  // the probe pressing it (needs soft_tissue); neither goes with the wire's or the heart's effects
  std::optional<soft_tissue::SoftTissueSpec> soft_tissue;
  std::optional<soft_tissue::ProbeContactParams> probe_contact;
};

}  // namespace pcisim::physics
