#include <algorithm>
#include <array>
#include <span>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <fstream>
#include <sstream>

#include "json/json_reader.h"
#include "json/regular_file.h"
#include "physics/guidewire/wire_presets.h"
#include "server/scene/scene.h"
#include "xray/projectors/trilinear_projector.h"

namespace pcisim::server {
namespace {

constexpr double kMm = 1e-3;

// a number within the component's own range (physics/*_params.h), in the scene's unit
double in_range(json::JsonReader& r, const std::string& key, double fallback, const physics::ParamRange& range,
                double scene_unit = 1.0) {
  // bounds in the scene's unit, rounded to 12 digits (0.05 mm, not 0.05000000000000001)
  auto tidy = [](double x) { return std::stod(fmt::format("{:.12g}", x)); };
  return r.number(key, fallback / scene_unit, tidy(range.min / scene_unit), tidy(range.max / scene_unit)) * scene_unit;
}
int in_range(json::JsonReader& r, const std::string& key, int fallback, const physics::ParamRange& range) {
  return r.integer(key, fallback, static_cast<int>(range.min), static_cast<int>(range.max));
}

physics::GuidewireParams read_guidewire(json::JsonReader r) {
  physics::GuidewireParams p;
  p.model = r.text("model", "chain_mail", {"chain_mail", "rod"}) == "rod" ? physics::GuidewireModel::kRod
                                                                          : physics::GuidewireModel::kChainMail;
  // a named wire sets the rod's section first; the keys below still override each field
  std::vector<std::string> presets = {"none"};
  for (const auto& w : physics::wire_presets()) presets.emplace_back(w.name);
  const std::string preset = r.text("preset", "none", presets);
  if (preset != "none") physics::apply_wire_preset(preset, &p);
  p.internal_force = r.text("internal_force", "refused_feed", {"refused_feed", "eq20"}) == "eq20"
                         ? physics::InternalForce::kEq20
                         : physics::InternalForce::kRefusedFeed;
  {
    const std::string limits = r.text("chain_mail_limits", "given", {"given", "nitinol_core", "steel_core"});
    p.chain_mail_limits = limits == "nitinol_core" ? physics::ChainMailLimits::kNitinolCore
                          : limits == "steel_core" ? physics::ChainMailLimits::kSteelCore
                                                   : physics::ChainMailLimits::kGiven;
  }
  // the rod feels the beat through the moving wall unless told otherwise; the chain-mail can only ride it
  const bool rod = p.model == physics::GuidewireModel::kRod;
  p.beat_coupling = r.text("beat_coupling", rod ? "contact" : "kinematic", {"contact", "kinematic"}) == "contact"
                        ? physics::BeatCoupling::kContact
                        : physics::BeatCoupling::kKinematic;
  if (!rod && p.beat_coupling == physics::BeatCoupling::kContact)
    r.fail("beat_coupling",
           "\"contact\" needs guidewire.model \"rod\" (the chain-mail rides the vessels: \"kinematic\")");
  // where the wall enters the rod's substep: after its solve (projection) or inside it (solve:
  // contact and friction on the rod's compliance; issue #33, docs/guidewire.md)
  p.rod_contact = r.text("rod_contact", "projection", {"projection", "solve"}) == "solve"
                      ? physics::RodContactScheme::kSolve
                      : physics::RodContactScheme::kProjection;
  if (!rod && p.rod_contact == physics::RodContactScheme::kSolve)
    r.fail("rod_contact",
           "\"solve\" needs guidewire.model \"rod\" (the chain-mail has no solve for the wall to enter)");
  p.length_m = in_range(r, "length_mm", p.length_m, physics::kGuidewireLengthM, kMm);
  p.segment_count = in_range(r, "segments", p.segment_count, physics::kGuidewireSegments);
  p.optimisation_passes =
      in_range(r, "optimisation_passes", p.optimisation_passes, physics::kGuidewireOptimisationPasses);
  p.tip_length_m = in_range(r, "tip_length_mm", p.tip_length_m, physics::kGuidewireTipLengthM, kMm);
  p.tip_angle_deg = in_range(r, "tip_angle_deg", p.tip_angle_deg, physics::kGuidewireTipAngleDeg);
  p.body_alpha_min = in_range(r, "body_alpha_min", p.body_alpha_min, physics::kGuidewireAlphaMin);
  p.body_alpha_max = in_range(r, "body_alpha_max", p.body_alpha_max, physics::kGuidewireAlphaMax);
  p.body_beta_deg_per_mm = in_range(r, "body_beta_deg_per_mm", p.body_beta_deg_per_mm, physics::kGuidewireBetaDegPerMm);
  p.tip_alpha_min = in_range(r, "tip_alpha_min", p.tip_alpha_min, physics::kGuidewireAlphaMin);
  p.tip_alpha_max = in_range(r, "tip_alpha_max", p.tip_alpha_max, physics::kGuidewireAlphaMax);
  p.tip_beta_deg_per_mm = in_range(r, "tip_beta_deg_per_mm", p.tip_beta_deg_per_mm, physics::kGuidewireBetaDegPerMm);
  p.axial_stiffness_n_per_m =
      in_range(r, "axial_stiffness_n_per_m", p.axial_stiffness_n_per_m, physics::kGuidewireAxialStiffnessNPerM);
  p.axial_damping_n_s_per_m =
      in_range(r, "axial_damping_n_s_per_m", p.axial_damping_n_s_per_m, physics::kGuidewireAxialDampingNSPerM);
  p.torsional_rigidity_nm2 =
      in_range(r, "torsional_rigidity_nm2", p.torsional_rigidity_nm2, physics::kGuidewireTorsionalRigidityNm2);
  p.torsion_damping_nm_s_per_rad = in_range(r, "torsion_damping_nm_s_per_rad", p.torsion_damping_nm_s_per_rad,
                                            physics::kGuidewireTorsionDampingNmSPerRad);
  // the rod model's section (ignored by the chain-mail)
  p.bending_stiffness_nm2 =
      in_range(r, "bending_stiffness_nm2", p.bending_stiffness_nm2, physics::kGuidewireBendingStiffnessNm2);
  p.tip_bending_stiffness_nm2 =
      in_range(r, "tip_bending_stiffness_nm2", p.tip_bending_stiffness_nm2, physics::kGuidewireBendingStiffnessNm2);
  p.mass_per_length_kg_per_m =
      in_range(r, "mass_per_length_kg_per_m", p.mass_per_length_kg_per_m, physics::kGuidewireMassPerLengthKgPerM);
  p.outer_diameter_m = in_range(r, "outer_diameter_mm", p.outer_diameter_m, physics::kGuidewireOuterDiameterM, kMm);
  p.rod_damping_per_s = in_range(r, "rod_damping_per_s", p.rod_damping_per_s, physics::kGuidewireRodDampingPerS);
  p.rod_substeps = in_range(r, "rod_substeps", p.rod_substeps, physics::kGuidewireRodSubsteps);
  p.rod_iterations = in_range(r, "rod_iterations", p.rod_iterations, physics::kGuidewireRodIterations);
  p.feed_refuse_force_n =
      in_range(r, "feed_refuse_force_n", p.feed_refuse_force_n, physics::kGuidewireFeedRefuseForceN);
  r.finish();
  if (p.tip_length_m >= p.length_m) r.fail("tip_length_mm", "expected less than length_mm");
  return p;
}

physics::VesselContactParams read_vessel_contact(json::JsonReader r) {
  physics::VesselContactParams p;
  p.sdf_spacing_m = in_range(r, "sdf_spacing_mm", p.sdf_spacing_m, physics::kContactSdfSpacingM, kMm);
  p.wall_margin_m = in_range(r, "wall_margin_mm", p.wall_margin_m, physics::kContactWallMarginM, kMm);
  p.wall_stiffness_n_per_m =
      in_range(r, "wall_stiffness_n_per_m", p.wall_stiffness_n_per_m, physics::kContactWallStiffnessNPerM);
  r.finish();
  return p;
}

physics::FrictionParams read_friction(json::JsonReader r) {
  physics::FrictionParams p;
  p.body_static = in_range(r, "body_static", p.body_static, physics::kFrictionCoefficient);
  p.body_kinetic = in_range(r, "body_kinetic", p.body_kinetic, physics::kFrictionCoefficient);
  p.tip_static = in_range(r, "tip_static", p.tip_static, physics::kFrictionCoefficient);
  p.tip_kinetic = in_range(r, "tip_kinetic", p.tip_kinetic, physics::kFrictionCoefficient);
  r.finish();
  if (p.body_kinetic > p.body_static) r.fail("body_kinetic", "expected at most body_static");
  if (p.tip_kinetic > p.tip_static) r.fail("tip_kinetic", "expected at most tip_static");
  return p;
}

physics::BloodFlowParams read_blood_flow(json::JsonReader r) {
  physics::BloodFlowParams p;
  p.mean_velocity_m_per_s =
      in_range(r, "mean_velocity_mm_s", p.mean_velocity_m_per_s, physics::kBloodMeanVelocityMPerS, kMm);
  p.drift_gain = in_range(r, "drift_gain", p.drift_gain, physics::kBloodDriftGain);
  p.pulsatility = in_range(r, "pulsatility", p.pulsatility, physics::kBloodPulsatility);
  p.cell_spacing_m = in_range(r, "cell_spacing_mm", p.cell_spacing_m, physics::kBloodCellSpacingM, kMm);
  p.link_radius_m = in_range(r, "link_radius_mm", p.link_radius_m, physics::kBloodLinkRadiusM, kMm);
  r.finish();
  return p;
}

physics::HeartBeatParams read_heart_beat(json::JsonReader r, const std::string& scene_dir) {
  physics::HeartBeatParams p;
  p.rate_bpm = in_range(r, "rate_bpm", p.rate_bpm, physics::kHeartRateBpm);
  p.motion_file = r.text("motion_file", "");
  // a relative motion file is found beside the scene file
  if (!p.motion_file.empty() && !scene_dir.empty() && std::filesystem::path(p.motion_file).is_relative())
    p.motion_file = (std::filesystem::path(scene_dir) / p.motion_file).string();
  std::error_code ec;
  if (!p.motion_file.empty() && (!std::filesystem::is_regular_file(p.motion_file, ec) || ec))
    r.fail("motion_file",
           fmt::format("expected a heart motion file (docs/heart.md), cannot read \"{}\"", p.motion_file));
  p.substeps = in_range(r, "substeps", p.substeps, physics::kHeartSubsteps);
  p.iterations = in_range(r, "iterations", p.iterations, physics::kHeartIterations);
  const std::string solver = r.text("solver", "jacobi", {"jacobi", "gauss_seidel", "jacobi_cuda"});
  p.solver = solver == "jacobi"        ? physics::pbd::SolverKind::kJacobi
             : solver == "jacobi_cuda" ? physics::pbd::SolverKind::kJacobiCuda
                                       : physics::pbd::SolverKind::kGaussSeidel;
  p.sor_w = in_range(r, "sor_w", p.sor_w, physics::kHeartSorW);
  p.stretch_compliance_m_per_n =
      in_range(r, "stretch_compliance_m_per_n", p.stretch_compliance_m_per_n, physics::kHeartStretchComplianceMPerN);
  p.bend_compliance_per_n_m =
      in_range(r, "bend_compliance_per_n_m", p.bend_compliance_per_n_m, physics::kHeartBendCompliancePerNM);
  p.shape_compliance_s2 = in_range(r, "shape_compliance_s2", p.shape_compliance_s2, physics::kHeartShapeComplianceS2);
  p.damping_per_s = in_range(r, "damping_per_s", p.damping_per_s, physics::kHeartDampingPerS);
  p.cluster_size_m =
      r.number("cluster_size_mm", p.cluster_size_m / kMm, 0, physics::kHeartClusterSizeM.max / kMm) * kMm;
  if (p.cluster_size_m > 0.0 && p.cluster_size_m < physics::kMinClusterSizeM)
    r.fail("cluster_size_mm",
           fmt::format("expected 0 (the global cluster only) or a number in [5, 200], got {}", p.cluster_size_m / kMm));
  r.finish();
  return p;
}

// effects.soft_tissue: the organ's particle model and its solver (physics/soft_tissue)
physics::soft_tissue::SoftTissueSpec read_soft_tissue(json::JsonReader r) {
  namespace st = physics::soft_tissue;
  st::SoftTissueSpec s;
  st::TissueModelSpec& m = s.model;
  m.particle_radius_m = in_range(r, "particle_radius_mm", 3.3e-3, st::kTissueParticleRadiusM, kMm);
  m.voxel_m = in_range(r, "voxel_mm", m.voxel_m, st::kTissueVoxelM, kMm);
  if (m.voxel_m > m.particle_radius_m) r.fail("voxel_mm", "expected at most particle_radius_mm");
  m.cluster_spacing_factor =
      in_range(r, "cluster_spacing_factor", m.cluster_spacing_factor, st::kTissueClusterSpacingFactor);
  m.cluster_overlap = in_range(r, "cluster_overlap", m.cluster_overlap, st::kTissueClusterOverlap);
  m.tet_spacing_factor = in_range(r, "tet_spacing_factor", m.tet_spacing_factor, st::kTissueTetSpacingFactor);
  s.settle_s = in_range(r, "settle_s", s.settle_s, st::kTissueSettleS);
  st::TissueParams& p = s.params;
  p.density_kg_per_m3 = in_range(r, "density_kg_per_m3", p.density_kg_per_m3, st::kTissueDensityKgPerM3);
  p.cluster_compliance_s2 =
      in_range(r, "cluster_compliance_s2", p.cluster_compliance_s2, st::kTissueClusterComplianceS2);
  p.bulk_modulus_pa = in_range(r, "bulk_modulus_pa", p.bulk_modulus_pa, st::kTissueBulkModulusPa);
  p.substeps = in_range(r, "substeps", p.substeps, st::kTissueSubsteps);
  p.iterations = in_range(r, "iterations", p.iterations, st::kTissueIterations);
  const std::string solver = r.text("solver", "gauss_seidel", {"gauss_seidel", "jacobi"});
  p.solver = solver == "jacobi" ? physics::pbd::SolverKind::kJacobi : physics::pbd::SolverKind::kGaussSeidel;
  // the whole step (clusters, volumes, contacts) on a CUDA device: the Jacobi solver's twin
  if (r.text("device", "cpu", {"cpu", "cuda"}) == "cuda") {
    if (r.has("solver") && solver != "jacobi")
      r.fail("device", "\"cuda\" solves with Jacobi: set solver \"jacobi\" or leave it out");
    p.solver = physics::pbd::SolverKind::kJacobiCuda;
  }
  p.sor_w = in_range(r, "sor_w", p.sor_w, st::kTissueSorW);
  p.stabilisation_iterations =
      in_range(r, "stabilisation_iterations", p.stabilisation_iterations, st::kTissueStabilisationIterations);
  p.damping_per_s = in_range(r, "damping_per_s", p.damping_per_s, st::kTissueDampingPerS);
  p.contact_radius_factor =
      in_range(r, "contact_radius_factor", p.contact_radius_factor, st::kTissueContactRadiusFactor);
  p.contact_surface = r.text("contact_surface", p.contact_surface == st::ContactSurface::kSkin ? "skin" : "spheres",
                             {"spheres", "skin"}) == "skin"
                          ? st::ContactSurface::kSkin
                          : st::ContactSurface::kSpheres;
  p.support_mu_static = in_range(r, "support_mu_static", p.support_mu_static, st::kTissueFriction);
  p.support_mu_kinetic = in_range(r, "support_mu_kinetic", p.support_mu_kinetic, st::kTissueFriction);
  if (p.support_mu_kinetic > p.support_mu_static) r.fail("support_mu_kinetic", "expected at most support_mu_static");
  p.probe_mu_static = in_range(r, "probe_mu_static", p.probe_mu_static, st::kTissueFriction);
  p.probe_mu_kinetic = in_range(r, "probe_mu_kinetic", p.probe_mu_kinetic, st::kTissueFriction);
  if (p.probe_mu_kinetic > p.probe_mu_static) r.fail("probe_mu_kinetic", "expected at most probe_mu_static");
  r.finish();
  return s;
}

// three numbers within +-limit (a probe position, mm)
Eigen::Vector3d read_vector3(json::JsonReader& r, const std::string& key, const Eigen::Vector3d& fallback,
                             double limit) {
  if (!r.has(key)) return fallback;
  Eigen::Vector3d out;
  if (!r.numbers(key, std::span<double>(out.data(), 3)) || out.cwiseAbs().maxCoeff() > limit)
    r.fail(key, r.list(key).size() != 3 ? std::string("expected [x, y, z]")
                                        : fmt::format("expected [x, y, z], each within +-{}", limit));
  return out;
}

// effects.probe_contact: the transducer block and where it waits before the probe's first sample
physics::soft_tissue::ProbeContactParams read_probe_contact(json::JsonReader r) {
  namespace st = physics::soft_tissue;
  st::ProbeContactParams p;
  p.face_width_m = in_range(r, "face_width_mm", p.face_width_m, st::kProbeFaceWidthM, kMm);
  p.face_thickness_m = in_range(r, "face_thickness_mm", p.face_thickness_m, st::kProbeFaceThicknessM, kMm);
  p.height_m = in_range(r, "height_mm", p.height_m, st::kProbeHeightM, kMm);
  p.start_position_m = read_vector3(r, "start_position_mm", p.start_position_m / kMm, 1e4) * kMm;
  if (p.start_position_m.norm() > 10.0) r.fail("start_position_mm", "expected within 10000 mm of the origin");
  if (r.has("start_orientation_wxyz")) {
    std::array<double, 4> q{};
    const bool ok = r.numbers("start_orientation_wxyz", q);
    const double norm = ok ? std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]) : 0.0;
    if (!ok || !(norm > 1e-6)) r.fail("start_orientation_wxyz", "expected a non-zero quaternion [w, x, y, z]");
    p.start_rotation = Eigen::Quaterniond(q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm);
  }
  p.max_stiffness_n_per_m = in_range(r, "max_stiffness_n_per_m", p.max_stiffness_n_per_m, st::kProbeMaxStiffnessNPerM);
  p.damping_n_s_per_m = in_range(r, "damping_n_s_per_m", p.damping_n_s_per_m, st::kProbeDampingNSPerM);
  r.finish();
  return p;
}

// effects.ultrasound: the machine's settings (ranges: ultrasound::validate, named on failure)
UltrasoundSpec read_ultrasound(json::JsonReader r) {
  UltrasoundSpec u;
  ultrasound::UsSettings& s = u.settings;
  s.geometry = r.text("geometry", "linear", {"linear", "curvilinear"}) == "curvilinear"
                   ? ultrasound::ProbeGeometry::kCurvilinear
                   : ultrasound::ProbeGeometry::kLinear;
  s.width_mm = r.number("width_mm", s.width_mm, 1e-3, 200);
  s.fan_angle_deg = r.number("fan_angle_deg", s.fan_angle_deg, 1e-3, 150);
  s.radius_of_curvature_mm = r.number("radius_of_curvature_mm", s.radius_of_curvature_mm, 1e-3, 200);
  s.depth_mm = r.number("depth_mm", s.depth_mm, 1, 300);
  s.width_px = r.integer("width_px", s.width_px, 8, 2048);
  s.height_px = r.integer("height_px", s.height_px, 8, 4096);
  s.gain_db = r.number("gain_db", s.gain_db, -60, 60);
  s.tgc_db_per_cm = r.number("tgc_db_per_cm", s.tgc_db_per_cm, -20, 40);
  s.frequency_mhz = r.number("frequency_mhz", s.frequency_mhz, 1, 20);
  s.attenuation_db_per_cm_mhz = r.number("attenuation_db_per_cm_mhz", s.attenuation_db_per_cm_mhz, 0, 5);
  s.dynamic_range_db = r.number("dynamic_range_db", s.dynamic_range_db, 10, 120);
  s.speckle_cell_mm = r.number("speckle_cell_mm", s.speckle_cell_mm, 0.02, 2);
  s.bandwidth = r.number("bandwidth", s.bandwidth, ultrasound::kUsBandwidthMin, ultrasound::kUsBandwidthMax);
  s.f_number = r.number("f_number", s.f_number, ultrasound::kUsFNumberMin, ultrasound::kUsFNumberMax);
  s.focus_mm = r.number("focus_mm", s.focus_mm, 1e-3, ultrasound::kUsMaxDepthMm);
  s.specular_exponent = r.number("specular_exponent", s.specular_exponent, 0, ultrasound::kUsSpecularExponentMax);
  s.threads = r.integer("threads", s.threads, 1, ultrasound::kUsMaxThreads);
  s.renderer = r.text("renderer", "cpu", {"cpu", "cuda"}) == "cuda" ? ultrasound::UsRenderer::kCuda
                                                                    : ultrasound::UsRenderer::kCpu;
  u.frame_rate_hz = r.number("frame_rate_hz", u.frame_rate_hz, 1, 60);
  u.speckle_seed = static_cast<uint32_t>(r.integer("speckle_seed", 1, 0, 1 << 30));
  r.finish();
  try {
    ultrasound::validate(s);
  } catch (const std::invalid_argument& e) {
    throw json::JsonError(fmt::format("effects.ultrasound: {}", e.what()));
  }
  return u;
}

physics::VesselMotionParams read_vessel_motion(json::JsonReader r) {
  physics::VesselMotionParams p;
  p.attach_distance_m = in_range(r, "attach_mm", p.attach_distance_m, physics::kMotionAttachDistanceM, kMm);
  p.fade_distance_m = in_range(r, "fade_mm", p.fade_distance_m, physics::kMotionFadeDistanceM, kMm);
  p.blend_radius_m = in_range(r, "blend_radius_mm", p.blend_radius_m, physics::kMotionBlendRadiusM, kMm);
  r.finish();
  return p;
}

haptics::HapticParams read_haptics(json::JsonReader r) {
  haptics::HapticParams p;
  p.peak_force_n = r.number("peak_force_n", p.peak_force_n, 0, 20);
  p.peak_torque_nm = r.number("peak_torque_nm", p.peak_torque_nm, 0, 1);
  p.slew_n_per_s = r.number("slew_n_per_s", p.slew_n_per_s, 1, 1e5);
  p.slew_nm_per_s = r.number("slew_nm_per_s", p.slew_nm_per_s, 1e-3, 1e3);
  p.blend_ms = r.number("blend_ms", p.blend_ms, 0, 100);
  p.fade_ms = r.number("fade_ms", p.fade_ms, 1, 2000);
  p.ramp_in_ms = r.number("ramp_in_ms", p.ramp_in_ms, 1, 5000);
  p.instrument_timeout_ms = r.number("instrument_timeout_ms", p.instrument_timeout_ms, 5, 1000);
  const std::string mode =
      r.text("interpolation", "local_model", {"local_model", "zero_order_hold", "linear_extrapolation"});
  p.interpolation = mode == "zero_order_hold"        ? haptics::Interpolation::kZeroOrderHold
                    : mode == "linear_extrapolation" ? haptics::Interpolation::kLinearExtrapolation
                                                     : haptics::Interpolation::kLocalModel;
  p.passivity = r.boolean("passivity", p.passivity);
  p.passivity_max_damping_n_s_per_m =
      r.number("passivity_max_damping_n_s_per_m", p.passivity_max_damping_n_s_per_m, 0, 1e5);
  p.passivity_max_damping_nm_s_per_rad =
      r.number("passivity_max_damping_nm_s_per_rad", p.passivity_max_damping_nm_s_per_rad, 0, 100);
  r.finish();
  return p;
}

XraySpec read_xray(json::JsonReader r) {
  XraySpec x;
  auto& f = x.fluoro;
  const std::string projector = r.text("projector", "cpu", {"cpu", "exact", "gl", "cuda"});
  f.projector.projector = projector == "exact"  ? xray::ProjectorKind::kExact
                          : projector == "cuda" ? xray::ProjectorKind::kCudaTrilinear
                          : projector == "gl"   ? xray::ProjectorKind::kGl
                                                : xray::ProjectorKind::kCpuTrilinear;
  // "planes": one sample where a ray crosses each voxel plane (the default); "steps": trilinear
  // samples every step_voxels (a scene that gives step_voxels asks for steps). The cpu and cuda
  // projectors only: exact integrates each voxel, gl steps by step_voxels
  const bool samples = projector == "cpu" || projector == "cuda";
  if (!samples && r.has("sampling"))
    r.fail("sampling", "only with projector \"cpu\" or \"cuda\" (\"" + projector + "\" has its own)");
  const std::string sampling =
      samples ? r.text("sampling", r.has("step_voxels") ? "steps" : "planes", {"planes", "steps"}) : "steps";
  if (sampling == "planes" && r.has("step_voxels"))
    r.fail("step_voxels",
           "no step_voxels with sampling \"planes\" (one sample per voxel plane); use sampling \"steps\"");
  f.projector.trilinear.slices = sampling == "planes";
  f.projector.trilinear.step_voxels =
      r.number("step_voxels", f.projector.trilinear.step_voxels, xray::kMinSceneStepVoxels, xray::kMaxSceneStepVoxels);
  const int px = r.integer("detector_px", f.c_arm.width, 16, 2048);
  f.c_arm.width = f.c_arm.height = px;
  f.c_arm.pixel_mm = r.number("pixel_mm", f.c_arm.pixel_mm, 0.05, 2);
  f.c_arm.source_to_image_mm = r.number("sid_mm", f.c_arm.source_to_image_mm, 500, 2000);
  f.c_arm.source_to_axis_mm = r.number("sad_mm", f.c_arm.source_to_axis_mm, 300, 1500);
  if (f.c_arm.source_to_axis_mm >= f.c_arm.source_to_image_mm) r.fail("sad_mm", "expected less than sid_mm");
  f.volume_spacing_mm = r.number("volume_spacing_mm", f.volume_spacing_mm, 0.3, 5);
  const int voxels = r.integer("volume_voxels", static_cast<int>(f.volume_dims[0]), 32, 1024);
  f.volume_dims = {voxels, voxels, voxels / 2};
  f.blur_sigma_px = r.number("blur_sigma_px", f.blur_sigma_px, 0, 10);
  f.photons_per_pixel = 0;  // noise only with the detector_noise effect
  x.pulse_rate_fps = r.number("pulse_rate_fps", x.pulse_rate_fps, 7.5, 30);
  if (x.pulse_rate_fps != 7.5 && x.pulse_rate_fps != 15 && x.pulse_rate_fps != 30)
    r.fail("pulse_rate_fps", fmt::format("expected 7.5, 15 or 30, got {}", x.pulse_rate_fps));
  x.cine_rate_fps = r.number("cine_rate_fps", x.cine_rate_fps, 7.5, 60);
  // the x-ray thread ticks at the faster rate and renders every n-th tick at the slower one, so
  // the faster must be a whole multiple of the slower (15 and 30 fps cine, say, not 25)
  const double ratio = std::max(x.pulse_rate_fps, x.cine_rate_fps) / std::min(x.pulse_rate_fps, x.cine_rate_fps);
  if (std::abs(ratio - std::round(ratio)) > 1e-9)
    r.fail("cine_rate_fps", fmt::format("expected a whole multiple or divisor of pulse_rate_fps ({}), got {}",
                                        x.pulse_rate_fps, x.cine_rate_fps));
  x.initial_pose.primary_deg = r.number("primary_deg", -30, -180, 180);
  x.initial_pose.secondary_deg = r.number("secondary_deg", 30, -90, 90);
  x.heart_phase_bins = static_cast<int>(r.integer("heart_phase_bins", x.heart_phase_bins, 0, 64));
  if (x.heart_phase_bins == 1) r.fail("heart_phase_bins", "expected 0 (a still background) or 2-64, got 1");
  x.heart_phase_blend = r.boolean("heart_phase_blend", x.heart_phase_blend);
  r.finish();
  return x;
}

// the cath lab's bounds on console commands (server/session_limits.h)
SessionLimitParams read_session(json::JsonReader r) {
  SessionLimitParams p;
  p.min_reset_interval_s = r.number("min_reset_interval_s", p.min_reset_interval_s, 0, 600);
  p.min_scene_load_interval_s = r.number("min_scene_load_interval_s", p.min_scene_load_interval_s, 0, 600);
  p.max_injections_per_min = static_cast<int>(r.integer("max_injections_per_min", p.max_injections_per_min, 1, 60));
  p.max_contrast_ml = r.number("max_contrast_ml", p.max_contrast_ml, 1, 2000);
  p.min_carm_move_interval_s = r.number("min_carm_move_interval_s", p.min_carm_move_interval_s, 0, 60);
  r.finish();
  return p;
}

// what the debrief judges against (server/debrief/debrief_params.h, docs/debrief.md)
DebriefParams read_debrief(json::JsonReader r) {
  DebriefParams p;
  p.target_branch = r.text("target_branch", "");
  p.tip_force_threshold_n = r.number("tip_force_threshold_n", p.tip_force_threshold_n, 0.001, 10);
  p.tip_force_risk_n = r.number("tip_force_risk_n", p.tip_force_risk_n, 0.001, 10);
  p.tube_output_ugy_per_mas_at_1m = r.number("tube_output_ugy_per_mas_at_1m", p.tube_output_ugy_per_mas_at_1m, 1, 500);
  p.fluoro_mas_per_pulse = r.number("fluoro_mas_per_pulse", p.fluoro_mas_per_pulse, 0.001, 10);
  p.cine_mas_per_frame = r.number("cine_mas_per_frame", p.cine_mas_per_frame, 0.001, 50);
  r.finish();
  return p;
}

void read_contrast(json::JsonReader r, XraySpec& x) {
  x.contrast = true;
  x.fluoro.iodine_mu_per_mm = r.number("iodine_mu_per_mm", x.fluoro.iodine_mu_per_mm, 0, 2);
  x.injection_volume_ml = r.number("injection_ml", x.injection_volume_ml, 0.5, 30);
  x.injection_duration_s = r.number("injection_s", x.injection_duration_s, 0.2, 10);
  r.finish();
}

void read_detector_noise(json::JsonReader r, XraySpec& x) {
  x.fluoro.photons_per_pixel = r.number("photons_per_pixel", 2000, 10, 1e7);
  r.finish();
}

// an effect's dependencies are checked here so the error names the scene path
void require(const Scene& s, const std::string& effect, const std::string& needs) {
  const auto& e = s.effects;
  if (std::find(e.begin(), e.end(), needs) == e.end())
    throw json::JsonError(fmt::format("effects.{}: needs effect \"{}\" in the same scene", effect, needs));
}

Scene parse(const nlohmann::json& doc, const std::string& source) {
  Scene s;
  const std::string scene_dir = source == "built-in" ? "" : std::filesystem::path(source).parent_path().string();
  s.source = source;
  json::JsonReader top(doc, "");
  s.name = top.text("name", "unnamed");
  s.physics_rate_hz = top.number("physics_rate_hz", s.physics_rate_hz, 1, 1000);
  s.world.step_s = 1.0 / s.physics_rate_hz;

  json::JsonReader anatomy = top.child("anatomy");
  // a case folder or a phantom seed, not both
  if (anatomy.has("case") && anatomy.has("phantom_seed"))
    anatomy.fail("case", "give either a case folder or a phantom_seed, not both");
  // the procedural kidney (soft-tissue scene), or a case folder that brings its own organ
  s.organ = anatomy.text("organ", "", {"", "kidney"});
  if (!s.organ.empty() && anatomy.has("case"))
    anatomy.fail("organ",
                 "give either the procedural \"kidney\" or a case folder (which brings its own organ), not both");
  s.world.anatomy.seed = static_cast<uint32_t>(anatomy.integer("phantom_seed", 1, 0, 1 << 30));
  if (anatomy.has("case")) {
    const std::string dir = anatomy.text("case", "");
    if (dir.empty()) anatomy.fail("case", "expected the path of a case folder");
    const std::filesystem::path p(dir);
    s.case_dir = p.is_absolute() || scene_dir.empty() ? p.string() : (std::filesystem::path(scene_dir) / p).string();
  }
  anatomy.finish();

  s.haptics = read_haptics(top.child("haptics"));
  s.session = read_session(top.child("session"));
  s.debrief = read_debrief(top.child("debrief"));

  if (!doc.contains("effects")) top.fail("effects", "expected an object listing the effects to simulate");
  json::JsonReader effects = top.child("effects");
  const auto& known = known_effects();
  for (const auto& [name, params] : doc.at("effects").items())
    if (std::find(known.begin(), known.end(), name) == known.end())
      effects.fail(name, fmt::format("unknown effect (known: {})", fmt::join(known, ", ")));
  for (const auto& name : known) {
    if (!effects.has(name)) continue;
    s.effects.push_back(name);
    json::JsonReader r = effects.child(name);
    if (name == "guidewire") s.world.guidewire = read_guidewire(r);
    if (name == "vessel_contact") s.world.vessel_contact = read_vessel_contact(r);
    if (name == "friction") s.world.friction = read_friction(r);
    if (name == "blood_flow") s.world.blood_flow = read_blood_flow(r);
    if (name == "heart_beat") s.world.heart_beat = read_heart_beat(r, scene_dir);
    if (name == "vessel_motion") s.world.vessel_motion = read_vessel_motion(r);
    if (name == "xray") s.xray = read_xray(r);
    if (name == "soft_tissue") s.world.soft_tissue = read_soft_tissue(r);
    if (name == "probe_contact") s.world.probe_contact = read_probe_contact(r);
    if (name == "ultrasound") s.ultrasound = read_ultrasound(r);
  }
  // the x-ray's options come after xray itself has been read
  if (s.xray && effects.has("contrast")) read_contrast(effects.child("contrast"), *s.xray);
  if (s.xray && effects.has("detector_noise")) read_detector_noise(effects.child("detector_noise"), *s.xray);
  top.finish();

  if (s.world.vessel_contact) require(s, "vessel_contact", "guidewire");
  if (s.world.friction) require(s, "friction", "vessel_contact");
  if (s.world.blood_flow) require(s, "blood_flow", "guidewire");
  if (s.world.vessel_motion) require(s, "vessel_motion", "heart_beat");
  if (s.world.probe_contact) require(s, "probe_contact", "soft_tissue");
  if (s.ultrasound) require(s, "ultrasound", "probe_contact");
  if (s.world.soft_tissue) {
    // the organ scene: an organ on its support, a probe, ultrasound; none of the heart's or wire's
    for (const char* other : {"guidewire", "heart_beat", "xray"})
      if (std::find(s.effects.begin(), s.effects.end(), other) != s.effects.end())
        throw json::JsonError(fmt::format(
            "effects.soft_tissue: does not go with effect \"{}\" (the soft-tissue scene's anatomy is an organ)",
            other));
    if (s.organ.empty() && s.case_dir.empty())
      throw json::JsonError(
          "effects.soft_tissue: needs an organ (anatomy.organ: \"kidney\", or anatomy.case: a case folder with an "
          "organ)");
  }
  if (!s.organ.empty() && !s.world.soft_tissue)
    throw json::JsonError("anatomy.organ: needs effect \"soft_tissue\" (an organ is the soft-tissue scene's anatomy)");
  for (const char* option : {"contrast", "detector_noise"})
    if (std::find(s.effects.begin(), s.effects.end(), option) != s.effects.end()) require(s, option, "xray");
  return s;
}

}  // namespace

const std::vector<std::string>& known_effects() {
  static const std::vector<std::string> names = {"heart_beat",     "vessel_motion", "guidewire",     "blood_flow",
                                                 "vessel_contact", "friction",      "xray",          "contrast",
                                                 "detector_noise", "soft_tissue",   "probe_contact", "ultrasound"};
  return names;
}

Scene parse_scene(const std::string& text, const std::string& source) {
  const nlohmann::json doc = json::parse_json_checked(text, source);
  try {
    return parse(doc, source);
  } catch (const json::JsonError& e) {
    throw json::JsonError(fmt::format("{}: {}", source, e.what()));
  }
}

Scene load_scene_file(const std::string& path) {
  // a regular file (a FIFO would block the reader); a scene is a page of JSON, and a huge file
  // would hold the LCM thread and its memory for seconds
  std::string text;
  try {
    text = json::read_regular_file(path, "the scene file", kMaxSceneFileBytes);
  } catch (const json::FileError& e) {
    throw json::JsonError(e.what());
  }
  return parse_scene(text, path);
}

Scene default_scene() {
  return parse_scene(default_scene_text(), "built-in");
}

}  // namespace pcisim::server
