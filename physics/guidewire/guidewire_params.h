#pragma once
// Scene parameters of the guidewire effects (chain-mail paper, sections III-IV).
// Defaults describe a 0.014" workhorse wire with a soft angled tip.

namespace pcisim::physics {

struct GuidewireParams {
  double length_m = 0.30;            // simulated distal length of the wire
  int segment_count = 200;           // chain-mail links
  int optimisation_passes = 2;       // physical-optimisation passes per step (eqs 5-10)
  double tip_length_m = 0.012;       // soft shaped tip
  double tip_angle_deg = 45.0;       // pre-bend of the tip
  // body / tip chain-mail limits: link length ratios and shear angle (eqs 1-4)
  double body_alpha_min = 0.98, body_alpha_max = 1.02, body_beta_deg = 2.0;
  double tip_alpha_min = 0.95, tip_alpha_max = 1.05, tip_beta_deg = 12.0;
};

struct VesselContactParams {
  double sdf_spacing_m = 0.2e-3;     // SDF grid spacing
  double wall_margin_m = 0.05e-3;    // epsilon of eq 15
  double wall_stiffness_n_per_m = 40.0;  // penalty stiffness for the haptic force (eqs 19-20)
};

struct FrictionParams {
  double body_static = 0.10, body_kinetic = 0.07;  // Coulomb coefficients, PTFE-coated body
  double tip_static = 0.20, tip_kinetic = 0.15;    // hydrophilic polymer tip
};

struct BloodFlowParams {
  double mean_velocity_m_per_s = 0.15;  // steady flow along the centerlines
  double drift_gain = 0.02;             // fraction of the flow velocity a free node drifts (eq 12)
};

}  // namespace pcisim::physics
