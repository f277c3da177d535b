#pragma once
// Scene parameters of the guidewire effects (chain-mail paper, sections III-V).
// Defaults describe a 0.014" workhorse wire with a soft angled tip.

#include "physics/param_checks.h"

namespace pcisim::physics {

// which wire model a scene runs (scene key guidewire.model): the chain-mail of the paper, or a
// discrete Cosserat rod with physical stiffness (physics/guidewire/rod_wire.h, docs/guidewire.md)
enum class GuidewireModel { kChainMail, kRod };

// the chain-mail's F_internal of [guidewire eq 19]: the feed the wire refused this step times
// the axial stiffness (today's variant), or [guidewire eq 20] as the paper writes it, k times the
// change of the first free link's length since the last step (docs/guidewire.md)
enum class InternalForce { kRefusedFeed, kEq20 };

// how the beating vessels move the wire (scene key guidewire.beat_coupling; docs/guidewire.md):
// kKinematic solves the wire in the vessels' rest frame and carries the solution into the world
// by the vessels' skin; kContact lets the wire live in the world, where the moving wall pushes it
// through contact and friction (rod model only)
enum class BeatCoupling { kKinematic, kContact };

// how the rod meets the wall (docs/guidewire.md): kProjection, the scenes' default, moves nodes
// out of the wall after each solve and decides friction on the rod's forces (the wall has the
// last word, so a pushed wire crumples); kSolve solves contact and Coulomb friction with the
// rod's elasticity on its contact compliance after the free solve (physics/rod/contact_pgs.h);
// kImplicit makes the wall and friction stiff springs inside the rod's own solve (issue #33).
// A scene picks kProjection (its default) or kSolve (guidewire.rod_contact); kImplicit is for
// the rigs only (each misses some of pcisim-bench wire-force's checks)
enum class RodContactScheme { kProjection, kSolve, kImplicit };

// where the chain-mail's limits come from: the alpha / beta fields as set, or derived from the
// rod section's bending stiffness for a nitinol or a stainless-steel core (chain_mail_limits.h)
enum class ChainMailLimits { kGiven, kNitinolCore, kSteelCore };

struct GuidewireParams {
  GuidewireModel model = GuidewireModel::kChainMail;
  InternalForce internal_force = InternalForce::kRefusedFeed;
  BeatCoupling beat_coupling = BeatCoupling::kKinematic;  // the scene loader's default is kContact for the rod
  // the chain-mail's alpha / beta limits as given below, or derived from the section's EI and a
  // core material (chain_mail_limits.h); scene key guidewire.chain_mail_limits
  ChainMailLimits chain_mail_limits = ChainMailLimits::kGiven;
  double length_m = 0.30;       // simulated distal length of the wire, (tip_length_m, 2]
  int segment_count = 200;      // chain-mail links, [4, 4000]
  int optimisation_passes = 2;  // physical-optimisation passes per step (eqs 5-10), [0, 64]
  double tip_length_m = 0.012;  // soft shaped tip, [0, length_m)
  double tip_angle_deg = 45.0;  // pre-bend of the tip, spread evenly over the tip, [0, 180]
  // body / tip chain-mail limits (eqs 1-4). alpha: link length ratios (compress, stretch),
  // alpha_min in [0.5, 1], alpha_max in [1, 2]. beta: largest bend of a link away from its rest
  // direction, in degrees per millimetre of wire (scaled by the link length, but never below
  // 1.5 mm of wire, so a segment sweep keeps the same wire: see link_spec.cc), [0, 90].
  double body_alpha_min = 0.98, body_alpha_max = 1.02, body_beta_deg_per_mm = 15.0;
  double tip_alpha_min = 0.95, tip_alpha_max = 1.05, tip_beta_deg_per_mm = 40.0;
  // haptic force (eqs 19-20): axial stiffness of the wire's refused feed and first link, N/m,
  // [0, 1e5]; damping along insertion, N s/m, [0, 100]
  double axial_stiffness_n_per_m = 200.0;
  double axial_damping_n_s_per_m = 0.5;
  // torsional rigidity GJ of the core, N m^2, [0, 1e-2]; rotational damping N m s/rad, [0, 1]
  double torsional_rigidity_nm2 = 1.2e-5;
  double torsion_damping_nm_s_per_rad = 1e-5;

  // --- the rod model's physical section (model kRod; the chain-mail ignores them) ---
  // bending stiffness EI of the body and of the tip, N m^2. Default body: a steel core of about
  // 0.2 mm (E 200 GPa, I = pi d^4 / 64), consistent with the torsional rigidity above (GJ / EI =
  // 2 G / E = 0.77 for a round isotropic core); tip: Euler's clamped-free buckling of 10 mm of
  // tip, EI = 4 L^2 P / pi^2, at a 1 gf tip load (docs/guidewire.md: presets with cited figures)
  double bending_stiffness_nm2 = 1.56e-5;
  double tip_bending_stiffness_nm2 = 4.0e-7;
  double mass_per_length_kg_per_m = 7.9e-4;  // a 0.356 mm steel wire (7900 kg/m^3)
  double outer_diameter_m = 0.356e-3;        // 0.014 inch
  // viscous drag of blood on the moving wire as a damping rate, 1/s: slender-body drag per
  // length c = 4 pi mu / ln(L / d) (mu 3.5 mPa s, L / d ~ 1000) over the mass per length, ~8/s
  double rod_damping_per_s = 8.0;
  int rod_substeps = 8;    // XPBD substeps per physics step (more when a step is long)
  int rod_iterations = 1;  // direct solves per substep, each followed by wall contact and friction
  RodContactScheme rod_contact = RodContactScheme::kProjection;
  // with rod_contact kSolve or kImplicit: how many times a substep may be halved and retried when
  // its contact is no longer a small linear problem (kSolve: a node near the wall moved far, or
  // the wall turned under it; kImplicit: a node left deep in the wall; rod_wire.cc); 0 keeps
  // every substep as rod_substeps sets it
  int rod_substep_halvings = 4;
  // with rod_contact kImplicit: the wall's stiffness, N/m (1 N leaves a node 0.01 mm into the
  // wall margin at 1e5), also the stiffness friction holds a stuck node with; and the most
  // solves of a substep while the contacts settle (the wall placed again where the nodes end)
  double rod_wall_stiffness_n_per_m = 1e5;
  int rod_contact_rounds = 6;
  // the hub lets the wire slip (refuses further feed) while the wire pushes back harder than
  // this: the grip of a torque device and the guide catheter's support are finite
  double feed_refuse_force_n = 1.0;
};

// axial and shear stiffness of the section, N: a 0.2 mm steel core (E A = 200 GPa x 3.1e-8 m^2;
// G A with kappa 0.9): the rod's
inline constexpr double kWireAxialStiffnessN = 6.3e3;
inline constexpr double kWireShearStiffnessN = 2.2e3;

// each field's range, the one source for validate() (link_spec.cc) and the scene loader
inline constexpr ParamRange kGuidewireLengthM{0.02, 2.0};
inline constexpr ParamRange kGuidewireSegments{4, 4000};
inline constexpr ParamRange kGuidewireOptimisationPasses{0, 64};
inline constexpr ParamRange kGuidewireTipLengthM{0.0, 0.1};  // and below length_m
inline constexpr ParamRange kGuidewireTipAngleDeg{0, 180};
inline constexpr ParamRange kGuidewireAlphaMin{0.5, 1.0};
inline constexpr ParamRange kGuidewireAlphaMax{1.0, 2.0};
inline constexpr ParamRange kGuidewireBetaDegPerMm{0, 90};
inline constexpr ParamRange kGuidewireAxialStiffnessNPerM{0, 1e5};
inline constexpr ParamRange kGuidewireAxialDampingNSPerM{0, 100};
inline constexpr ParamRange kGuidewireTorsionalRigidityNm2{0, 1e-2};
inline constexpr ParamRange kGuidewireTorsionDampingNmSPerRad{0, 1};
inline constexpr ParamRange kGuidewireBendingStiffnessNm2{1e-9, 1e-2};
inline constexpr ParamRange kGuidewireMassPerLengthKgPerM{1e-5, 1e-1};
inline constexpr ParamRange kGuidewireOuterDiameterM{1e-4, 3e-3};
inline constexpr ParamRange kGuidewireRodDampingPerS{0, 1000};
inline constexpr ParamRange kGuidewireRodSubsteps{1, 100};
inline constexpr ParamRange kGuidewireRodIterations{1, 20};
inline constexpr ParamRange kGuidewireRodSubstepHalvings{0, 6};
inline constexpr ParamRange kGuidewireRodWallStiffnessNPerM{1e2, 1e8};
inline constexpr ParamRange kGuidewireRodContactRounds{1, 20};
inline constexpr ParamRange kGuidewireFeedRefuseForceN{0.01, 100};

struct VesselContactParams {
  double sdf_spacing_m = 0.2e-3;   // SDF grid spacing
  double wall_margin_m = 0.05e-3;  // epsilon of eq 15
  // penalty stiffness turning the wall and friction corrections (metres) into the haptic force
  // (eqs 19-20), N/m, [0, 1e5]: 1000 N/m gives tenths of a newton of friction down a coronary
  double wall_stiffness_n_per_m = 1000.0;
};

struct FrictionParams {
  double body_static = 0.10, body_kinetic = 0.07;  // Coulomb coefficients, PTFE-coated body
  double tip_static = 0.20, tip_kinetic = 0.15;    // hydrophilic polymer tip
};

struct BloodFlowParams {
  double mean_velocity_m_per_s = 0.15;  // cross-section and cycle mean flow along the centerlines
  // fraction of the linked blood's velocity a free node takes (eq 12); the linked chain-mails
  // move at 1.3-2x the mean (Poiseuille), so this keeps the drift of the earlier steady model
  double drift_gain = 0.0125;
  // how much the flow swings with the cardiac cycle (needs heart_beat, else the flow is steady):
  // systole carries 1 - pulsatility of the mean, diastole the rest (coronary flow is diastolic)
  double pulsatility = 0.4;
  double cell_spacing_m = 1e-3;   // blood chain-mails along each centerline
  double link_radius_m = 1.5e-3;  // blood chain-mails this close to a wire node link to it (eq 12)
};

// ranges of the contact, friction and blood fields (one source for World's validation and the
// scene loader); a kinetic coefficient is also at most its static one
inline constexpr ParamRange kContactSdfSpacingM{5e-5, 2e-3};
inline constexpr ParamRange kContactWallMarginM{0, 1e-3};
inline constexpr ParamRange kContactWallStiffnessNPerM{0, 1e5};
inline constexpr ParamRange kFrictionCoefficient{0, 2};
inline constexpr ParamRange kBloodMeanVelocityMPerS{0, 2};
inline constexpr ParamRange kBloodDriftGain{0, 1};
inline constexpr ParamRange kBloodPulsatility{0, 1};
inline constexpr ParamRange kBloodCellSpacingM{2e-4, 5e-3};
inline constexpr ParamRange kBloodLinkRadiusM{2e-4, 5e-3};

}  // namespace pcisim::physics
