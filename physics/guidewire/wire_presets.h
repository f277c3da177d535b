#pragma once
// Named 0.014-inch coronary wires for the rod model (scene key guidewire.preset; issue #15
// item 1). A preset sets the rod's section; the scene's own keys still override each field.
// Each preset's tip stiffness comes from a manufacturer-stated tip load; the body's is the
// default steel-core estimate (no measured EI of a coronary wire was found): docs/guidewire.md.
#include <span>
#include <string>
#include <string_view>

#include "physics/guidewire/guidewire_params.h"

namespace pcisim::physics {

struct WirePreset {
  std::string_view name;         // the scene's value
  std::string_view modelled_on;  // the wire whose stated tip load it uses
  double tip_load_gf;            // stated tip load, gram-force
  double body_stiffness_scale;   // body EI and GJ as a multiple of GuidewireParams' defaults
};

// the presets, in the order docs/guidewire.md lists them
std::span<const WirePreset> wire_presets();

// The tip's bending stiffness from a tip load: the tip as a clamped-free column of tip_length_m
// buckling under the load, P = pi^2 EI / (4 L^2) (Euler), so EI = 4 L^2 P / pi^2. A modelling
// choice: makers measure tip load differently (docs/guidewire.md).
double tip_stiffness_from_load_nm2(double tip_load_gf, double tip_length_m);

// sets params' rod section from the named preset; throws std::invalid_argument naming the known
// presets when the name is not one of them
void apply_wire_preset(std::string_view name, GuidewireParams* params);

}  // namespace pcisim::physics
