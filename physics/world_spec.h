#pragma once
// What a scene asks physics to build. An effect is present exactly when its optional is set:
// an effect the scene does not list is never constructed.
#include <cstdint>
#include <optional>

#include "physics/guidewire/guidewire_params.h"

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
  std::optional<BloodFlowParams> blood_flow;          // needs guidewire
};

}  // namespace pcisim::physics
