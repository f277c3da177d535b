#pragma once
// The chain-mail's limits derived from the wire's physical section (issue #15, item 1;
// docs/guidewire.md, "The chain-mail's limits from the section"). The chain-mail has no forces,
// only limits [guidewire eqs 1-4], so a section maps onto them through what bounds a real wire's
// shape, not through its load response:
//   alpha  a link stretches or compresses by at most the core's axial strain under the largest
//          axial load the hub hands on (feed_refuse_force_n): alpha = 1 -+ F / (E pi d^2 / 4),
//          d the core's diameter below (body and tip each their own)
//   beta   a link bends by at most what the core takes elastically. The core's diameter follows
//          from EI = E pi d^4 / 64; its surface strain d kappa / 2 may reach the material's
//          recoverable strain eps, so kappa_max = 2 eps / d, and beta is kappa_max per millimetre
//          of wire (body from the body's EI, tip from the tip's)
// Material figures (docs/guidewire.md cites them): nitinol E 60 GPa, recoverable 6 %; stainless
// spring steel E 200 GPa, elastic to 0.6 %.
#include "physics/guidewire/guidewire_params.h"

namespace pcisim::physics {

struct CoreMaterial {
  double youngs_modulus_pa = 0.0;
  double recoverable_strain = 0.0;
};
CoreMaterial core_material(ChainMailLimits limits);  // kGiven: all zero

struct DerivedChainMailLimits {
  double body_alpha_min = 1.0, body_alpha_max = 1.0, body_beta_deg_per_mm = 0.0;
  double tip_alpha_min = 1.0, tip_alpha_max = 1.0, tip_beta_deg_per_mm = 0.0;
  double body_core_diameter_m = 0.0, tip_core_diameter_m = 0.0;
};

// the limits for p's section and core (p.chain_mail_limits must not be kGiven); beta capped at
// the scene range's 90 deg per mm, alpha inside [0.5, 2]
DerivedChainMailLimits derive_chain_mail_limits(const GuidewireParams& p);

// p's alpha / beta fields replaced by the derived ones unless p.chain_mail_limits is kGiven
void apply_chain_mail_limits(GuidewireParams* p);

}  // namespace pcisim::physics
