#include "physics/guidewire/wire_presets.h"

#include <array>
#include <numbers>
#include <stdexcept>

namespace pcisim::physics {
namespace {

constexpr double kGramForceN = 9.80665e-3;
// the free tip length of the tip-load convention used here (docs/guidewire.md)
constexpr double kTipLoadLengthM = 0.010;

// tip loads as stated by the makers, compiled in the guidewire-reference app's data file
// (github.com/JohnWang-98/guidewire, application/views/library/LibraryData.jsx; a secondary
// source, to check against the instructions for use): Abbott BMW 0.6 gf, Asahi Fielder FC 0.8 gf,
// Abbott Iron Man 1.0 gf, Asahi Miracle 6 6 gf
constexpr std::array<WirePreset, 4> kPresets{{
    {"workhorse", "Abbott Hi-Torque BMW", 0.6, 1.0},
    {"hydrophilic", "Asahi Fielder FC (polymer jacket)", 0.8, 1.0},
    // a support wire's body is stiffer; how much is not from a measurement (x 3, an assumption)
    {"support", "Abbott Iron Man", 1.0, 3.0},
    {"stiff_tip", "Asahi Miracle 6", 6.0, 1.0},
}};

}  // namespace

std::span<const WirePreset> wire_presets() {
  return kPresets;
}

double tip_stiffness_from_load_nm2(double tip_load_gf, double tip_length_m) {
  const double p_n = tip_load_gf * kGramForceN;
  return 4.0 * tip_length_m * tip_length_m * p_n / (std::numbers::pi * std::numbers::pi);
}

void apply_wire_preset(std::string_view name, GuidewireParams* params) {
  for (const WirePreset& p : kPresets) {
    if (p.name != name) continue;
    const GuidewireParams defaults;
    params->bending_stiffness_nm2 = p.body_stiffness_scale * defaults.bending_stiffness_nm2;
    params->torsional_rigidity_nm2 = p.body_stiffness_scale * defaults.torsional_rigidity_nm2;
    params->tip_bending_stiffness_nm2 = tip_stiffness_from_load_nm2(p.tip_load_gf, kTipLoadLengthM);
    return;
  }
  std::string known;
  for (const WirePreset& p : kPresets) known += (known.empty() ? "" : ", ") + std::string(p.name);
  throw std::invalid_argument("guidewire preset '" + std::string(name) + "': expected one of " + known);
}

}  // namespace pcisim::physics
