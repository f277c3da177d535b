#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <fstream>
#include <sstream>

#include "server/scene/json_reader.h"
#include "server/scene/scene.h"

namespace pcisim::server {
namespace {

constexpr double kMm = 1e-3;

physics::GuidewireParams read_guidewire(JsonReader r) {
  physics::GuidewireParams p;
  p.length_m = r.number("length_mm", p.length_m / kMm, 20, 2000) * kMm;
  p.segment_count = r.integer("segments", p.segment_count, 4, 4000);
  p.optimisation_passes = r.integer("optimisation_passes", p.optimisation_passes, 0, 64);
  p.tip_length_m = r.number("tip_length_mm", p.tip_length_m / kMm, 0, 100) * kMm;
  p.tip_angle_deg = r.number("tip_angle_deg", p.tip_angle_deg, 0, 180);
  p.body_alpha_min = r.number("body_alpha_min", p.body_alpha_min, 0.5, 1.0);
  p.body_alpha_max = r.number("body_alpha_max", p.body_alpha_max, 1.0, 2.0);
  p.body_beta_deg = r.number("body_beta_deg", p.body_beta_deg, 0, 90);
  p.tip_alpha_min = r.number("tip_alpha_min", p.tip_alpha_min, 0.5, 1.0);
  p.tip_alpha_max = r.number("tip_alpha_max", p.tip_alpha_max, 1.0, 2.0);
  p.tip_beta_deg = r.number("tip_beta_deg", p.tip_beta_deg, 0, 90);
  r.finish();
  if (p.tip_length_m >= p.length_m) r.fail("tip_length_mm", "expected less than length_mm");
  return p;
}

physics::VesselContactParams read_vessel_contact(JsonReader r) {
  physics::VesselContactParams p;
  p.sdf_spacing_m = r.number("sdf_spacing_mm", p.sdf_spacing_m / kMm, 0.02, 2.0) * kMm;
  p.wall_margin_m = r.number("wall_margin_mm", p.wall_margin_m / kMm, 0.0, 1.0) * kMm;
  p.wall_stiffness_n_per_m = r.number("wall_stiffness_n_per_m", p.wall_stiffness_n_per_m, 0, 1e5);
  r.finish();
  return p;
}

physics::FrictionParams read_friction(JsonReader r) {
  physics::FrictionParams p;
  p.body_static = r.number("body_static", p.body_static, 0, 2);
  p.body_kinetic = r.number("body_kinetic", p.body_kinetic, 0, 2);
  p.tip_static = r.number("tip_static", p.tip_static, 0, 2);
  p.tip_kinetic = r.number("tip_kinetic", p.tip_kinetic, 0, 2);
  r.finish();
  if (p.body_kinetic > p.body_static) r.fail("body_kinetic", "expected at most body_static");
  if (p.tip_kinetic > p.tip_static) r.fail("tip_kinetic", "expected at most tip_static");
  return p;
}

physics::BloodFlowParams read_blood_flow(JsonReader r) {
  physics::BloodFlowParams p;
  p.mean_velocity_m_per_s = r.number("mean_velocity_mm_s", p.mean_velocity_m_per_s / kMm, 0, 2000) * kMm;
  p.drift_gain = r.number("drift_gain", p.drift_gain, 0, 1);
  r.finish();
  return p;
}

haptics::HapticParams read_haptics(JsonReader r) {
  haptics::HapticParams p;
  p.peak_force_n = r.number("peak_force_n", p.peak_force_n, 0, 20);
  p.peak_torque_nm = r.number("peak_torque_nm", p.peak_torque_nm, 0, 1);
  p.slew_n_per_s = r.number("slew_n_per_s", p.slew_n_per_s, 1, 1e5);
  p.slew_nm_per_s = r.number("slew_nm_per_s", p.slew_nm_per_s, 1e-3, 1e3);
  p.blend_ms = r.number("blend_ms", p.blend_ms, 0, 100);
  p.fade_ms = r.number("fade_ms", p.fade_ms, 1, 2000);
  p.ramp_in_ms = r.number("ramp_in_ms", p.ramp_in_ms, 1, 5000);
  p.instrument_timeout_ms = r.number("instrument_timeout_ms", p.instrument_timeout_ms, 5, 1000);
  const std::string mode = r.text("interpolation", "local_model", {"local_model", "zero_order_hold", "linear_extrapolation"});
  p.interpolation = mode == "zero_order_hold"        ? haptics::Interpolation::kZeroOrderHold
                    : mode == "linear_extrapolation" ? haptics::Interpolation::kLinearExtrapolation
                                                     : haptics::Interpolation::kLocalModel;
  p.passivity = r.boolean("passivity", p.passivity);
  p.passivity_max_damping_n_s_per_m = r.number("passivity_max_damping_n_s_per_m", p.passivity_max_damping_n_s_per_m, 0, 1e5);
  p.passivity_max_damping_nm_s_per_rad =
      r.number("passivity_max_damping_nm_s_per_rad", p.passivity_max_damping_nm_s_per_rad, 0, 100);
  r.finish();
  return p;
}

// an effect's dependencies are checked here so the error names the scene path
void require(const Scene& s, const std::string& effect, const std::string& needs) {
  const auto& e = s.effects;
  if (std::find(e.begin(), e.end(), needs) == e.end())
    throw SceneError(fmt::format("effects.{}: needs effect \"{}\" in the same scene", effect, needs));
}

Scene parse(const nlohmann::json& doc, const std::string& source) {
  Scene s;
  s.source = source;
  JsonReader top(doc, "");
  s.name = top.text("name", "unnamed");
  s.physics_rate_hz = top.number("physics_rate_hz", s.physics_rate_hz, 1, 1000);
  s.world.step_s = 1.0 / s.physics_rate_hz;

  JsonReader anatomy = top.child("anatomy");
  s.world.anatomy.seed = static_cast<uint32_t>(anatomy.integer("phantom_seed", 1, 0, 1 << 30));
  anatomy.finish();

  s.haptics = read_haptics(top.child("haptics"));

  if (!doc.contains("effects")) top.fail("effects", "expected an object listing the effects to simulate");
  JsonReader effects = top.child("effects");
  const auto& known = known_effects();
  for (const auto& [name, params] : doc.at("effects").items())
    if (std::find(known.begin(), known.end(), name) == known.end())
      effects.fail(name, fmt::format("unknown effect (known: {})", fmt::join(known, ", ")));
  for (const auto& name : known) {
    if (!effects.has(name)) continue;
    s.effects.push_back(name);
    JsonReader r = effects.child(name);
    if (name == "guidewire") s.world.guidewire = read_guidewire(r);
    if (name == "vessel_contact") s.world.vessel_contact = read_vessel_contact(r);
    if (name == "friction") s.world.friction = read_friction(r);
    if (name == "blood_flow") s.world.blood_flow = read_blood_flow(r);
  }
  top.finish();

  if (s.world.vessel_contact) require(s, "vessel_contact", "guidewire");
  if (s.world.friction) require(s, "friction", "vessel_contact");
  if (s.world.blood_flow) require(s, "blood_flow", "guidewire");
  return s;
}

}  // namespace

const std::vector<std::string>& known_effects() {
  static const std::vector<std::string> names = {"guidewire", "blood_flow", "vessel_contact", "friction"};
  return names;
}

Scene parse_scene(const std::string& text, const std::string& source) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text, nullptr, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& e) {
    throw SceneError(fmt::format("{}: not valid JSON (byte {}): {}", source, e.byte, e.what()));
  }
  try {
    return parse(doc, source);
  } catch (const SceneError& e) {
    throw SceneError(fmt::format("{}: {}", source, e.what()));
  }
}

Scene load_scene_file(const std::string& path) {
  std::ifstream in(path);
  if (!std::filesystem::is_regular_file(path) || !in)
    throw SceneError(fmt::format("{}: cannot read the scene file (missing or not a file)", path));
  std::stringstream text;
  text << in.rdbuf();
  return parse_scene(text.str(), path);
}

Scene default_scene() { return parse_scene(default_scene_text(), "built-in"); }

}  // namespace pcisim::server
