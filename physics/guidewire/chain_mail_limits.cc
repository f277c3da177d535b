#include "physics/guidewire/chain_mail_limits.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace pcisim::physics {

CoreMaterial core_material(ChainMailLimits limits) {
  switch (limits) {
    case ChainMailLimits::kNitinolCore:
      return {60e9, 0.06};
    case ChainMailLimits::kSteelCore:
      return {200e9, 0.006};
    case ChainMailLimits::kGiven:
      break;
  }
  return {};
}

namespace {

// d from EI = E pi d^4 / 64
double core_diameter_m(double ei_nm2, double e_pa) {
  return std::pow(64.0 * ei_nm2 / (std::numbers::pi * e_pa), 0.25);
}

// kappa_max = 2 eps / d, in degrees per millimetre, within the scene's range
double beta_deg_per_mm(double d_m, double eps) {
  const double kappa_per_m = 2.0 * eps / d_m;
  return std::min(kappa_per_m * 180.0 / std::numbers::pi * 1e-3, kGuidewireBetaDegPerMm.max);
}

}  // namespace

DerivedChainMailLimits derive_chain_mail_limits(const GuidewireParams& p) {
  const CoreMaterial m = core_material(p.chain_mail_limits);
  if (!(m.youngs_modulus_pa > 0.0))
    throw std::invalid_argument("guidewire.chain_mail_limits: no core material to derive from");
  DerivedChainMailLimits d;
  d.body_core_diameter_m = core_diameter_m(p.bending_stiffness_nm2, m.youngs_modulus_pa);
  d.tip_core_diameter_m = core_diameter_m(p.tip_bending_stiffness_nm2, m.youngs_modulus_pa);
  // alpha: the core's axial strain, F / (E pi d^2 / 4), under the largest load the hub passes on
  auto strain = [&](double d_m) {
    return p.feed_refuse_force_n / (m.youngs_modulus_pa * std::numbers::pi * d_m * d_m / 4.0);
  };
  d.body_alpha_min = std::max(1.0 - strain(d.body_core_diameter_m), kGuidewireAlphaMin.min);
  d.body_alpha_max = std::min(1.0 + strain(d.body_core_diameter_m), kGuidewireAlphaMax.max);
  d.tip_alpha_min = std::max(1.0 - strain(d.tip_core_diameter_m), kGuidewireAlphaMin.min);
  d.tip_alpha_max = std::min(1.0 + strain(d.tip_core_diameter_m), kGuidewireAlphaMax.max);
  // beta: the core's elastic bend
  d.body_beta_deg_per_mm = beta_deg_per_mm(d.body_core_diameter_m, m.recoverable_strain);
  d.tip_beta_deg_per_mm = beta_deg_per_mm(d.tip_core_diameter_m, m.recoverable_strain);
  return d;
}

void apply_chain_mail_limits(GuidewireParams* p) {
  if (p->chain_mail_limits == ChainMailLimits::kGiven) return;
  const DerivedChainMailLimits d = derive_chain_mail_limits(*p);
  p->body_alpha_min = d.body_alpha_min;
  p->body_alpha_max = d.body_alpha_max;
  p->body_beta_deg_per_mm = d.body_beta_deg_per_mm;
  p->tip_alpha_min = d.tip_alpha_min;
  p->tip_alpha_max = d.tip_alpha_max;
  p->tip_beta_deg_per_mm = d.tip_beta_deg_per_mm;
}

}  // namespace pcisim::physics
