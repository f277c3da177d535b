#include "physics/guidewire/link_spec.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "physics/guidewire/chain_mail_limits.h"

namespace pcisim::physics {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// the length of wire over which the shear limit beta (degrees per millimetre) is resolved. A
// joint's cone is beta times its link length, but never narrower than what this much wire may
// turn: a wall or friction correction of depth d at one node kinks its joint by about d / h,
// so a cone of beta h shrinks faster (h^2) than the kinks it must admit as links get shorter,
// and the limit sweep then straightens the kink by swinging the wire beyond it back into the
// wall. 1.5 mm is the link of the default 200-segment wire, which is unchanged by this.
constexpr double kShearLengthM = 1.5e-3;

void check(bool ok, const char* field, const char* expected) {
  if (!ok) throw std::invalid_argument(std::string("guidewire.") + field + ": expected " + expected);
}

}  // namespace

void validate(const GuidewireParams& p) {
  auto in_range = [](double v, const ParamRange& r, const char* field) {
    check(r.contains(v), field, r.describe().c_str());
  };
  in_range(p.length_m, kGuidewireLengthM, "length_m");
  in_range(p.segment_count, kGuidewireSegments, "segment_count");
  in_range(p.optimisation_passes, kGuidewireOptimisationPasses, "optimisation_passes");
  in_range(p.tip_length_m, kGuidewireTipLengthM, "tip_length_m");
  check(p.tip_length_m < p.length_m, "tip_length_m", "below length_m");
  in_range(p.tip_angle_deg, kGuidewireTipAngleDeg, "tip_angle_deg");
  in_range(p.body_alpha_min, kGuidewireAlphaMin, "body_alpha_min");
  in_range(p.body_alpha_max, kGuidewireAlphaMax, "body_alpha_max");
  in_range(p.tip_alpha_min, kGuidewireAlphaMin, "tip_alpha_min");
  in_range(p.tip_alpha_max, kGuidewireAlphaMax, "tip_alpha_max");
  in_range(p.body_beta_deg_per_mm, kGuidewireBetaDegPerMm, "body_beta_deg_per_mm");
  in_range(p.tip_beta_deg_per_mm, kGuidewireBetaDegPerMm, "tip_beta_deg_per_mm");
  in_range(p.axial_stiffness_n_per_m, kGuidewireAxialStiffnessNPerM, "axial_stiffness_n_per_m");
  in_range(p.axial_damping_n_s_per_m, kGuidewireAxialDampingNSPerM, "axial_damping_n_s_per_m");
  in_range(p.torsional_rigidity_nm2, kGuidewireTorsionalRigidityNm2, "torsional_rigidity_nm2");
  in_range(p.torsion_damping_nm_s_per_rad, kGuidewireTorsionDampingNmSPerRad, "torsion_damping_nm_s_per_rad");
  check(p.model == GuidewireModel::kChainMail || p.model == GuidewireModel::kRod, "model", "chain_mail or rod");
  check(p.internal_force == InternalForce::kRefusedFeed || p.internal_force == InternalForce::kEq20, "internal_force",
        "refused_feed or eq20");
  check(p.chain_mail_limits == ChainMailLimits::kGiven || p.chain_mail_limits == ChainMailLimits::kNitinolCore ||
            p.chain_mail_limits == ChainMailLimits::kSteelCore,
        "chain_mail_limits", "given, nitinol_core or steel_core");
  check(p.beat_coupling == BeatCoupling::kKinematic ||
            (p.beat_coupling == BeatCoupling::kContact && p.model == GuidewireModel::kRod),
        "beat_coupling", "kinematic, or contact with the rod model (the chain-mail rides the vessels kinematically)");
  check(p.rod_contact == RodContactScheme::kProjection || p.model == GuidewireModel::kRod, "rod_contact",
        "projection with the chain-mail (solve and implicit are the rod's)");
  in_range(p.bending_stiffness_nm2, kGuidewireBendingStiffnessNm2, "bending_stiffness_nm2");
  in_range(p.tip_bending_stiffness_nm2, kGuidewireBendingStiffnessNm2, "tip_bending_stiffness_nm2");
  in_range(p.mass_per_length_kg_per_m, kGuidewireMassPerLengthKgPerM, "mass_per_length_kg_per_m");
  in_range(p.outer_diameter_m, kGuidewireOuterDiameterM, "outer_diameter_m");
  in_range(p.rod_damping_per_s, kGuidewireRodDampingPerS, "rod_damping_per_s");
  in_range(p.rod_substeps, kGuidewireRodSubsteps, "rod_substeps");
  in_range(p.rod_iterations, kGuidewireRodIterations, "rod_iterations");
  in_range(p.rod_substep_halvings, kGuidewireRodSubstepHalvings, "rod_substep_halvings");
  in_range(p.rod_wall_stiffness_n_per_m, kGuidewireRodWallStiffnessNPerM, "rod_wall_stiffness_n_per_m");
  in_range(p.rod_contact_rounds, kGuidewireRodContactRounds, "rod_contact_rounds");
  in_range(p.feed_refuse_force_n, kGuidewireFeedRefuseForceN, "feed_refuse_force_n");
  if (p.model == GuidewireModel::kRod)
    check(p.torsional_rigidity_nm2 > 0.0, "torsional_rigidity_nm2", "above 0 for the rod");
}

std::vector<LinkSpec> make_link_specs(const GuidewireParams& given) {
  validate(given);
  // the limits as set, or derived from the section (chain_mail_limits.h)
  GuidewireParams p = given;
  apply_chain_mail_limits(&p);
  const int n = p.segment_count;
  const double h = p.length_m / n;
  const double shear_mm = std::max(h, kShearLengthM) * 1e3;
  // links touching the last tip_length_m are tip links; a non-zero tip gets at least one
  int tip_links = static_cast<int>(std::ceil(p.tip_length_m / h - 1e-9));
  if (p.tip_length_m > 0.0) tip_links = std::max(tip_links, 1);
  tip_links = std::min(tip_links, n - 1);
  // the pre-bend is spread evenly over the joints inside the tip (a smooth angled shape)
  const double bend_per_link = tip_links > 0 ? p.tip_angle_deg * kDeg / tip_links : 0.0;

  std::vector<LinkSpec> links(n);
  for (int j = 0; j < n; ++j) {
    LinkSpec& l = links[j];
    l.tip = j >= n - tip_links;
    l.rest_m = h;
    l.length_min_m = (l.tip ? p.tip_alpha_min : p.body_alpha_min) * h;
    l.length_max_m = (l.tip ? p.tip_alpha_max : p.body_alpha_max) * h;
    // beta is given per millimetre of wire, resolved over at least kShearLengthM; a link never
    // bends more than a right angle
    l.beta_rad =
        std::min((l.tip ? p.tip_beta_deg_per_mm : p.body_beta_deg_per_mm) * kDeg * shear_mm, std::numbers::pi / 2);
    l.cos_beta = std::cos(l.beta_rad);
    l.bend_rad = l.tip ? bend_per_link : 0.0;
    l.cos_bend = std::cos(l.bend_rad);
    l.sin_bend = std::sin(l.bend_rad);
  }
  return links;
}

}  // namespace pcisim::physics
