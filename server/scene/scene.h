#pragma once
// A scene: anatomy, instrument limits and the list of effects with their parameters.
// The server builds exactly the listed effects.
#include <cstdint>
#include <string>
#include <vector>

#include <optional>

#include "haptics/haptic_params.h"
#include "server/debrief/debrief_params.h"
#include "server/session_limits.h"
#include "physics/world_spec.h"
#include "ultrasound/probe/us_settings.h"
#include "xray/fluoro/fluoroscopy.h"

namespace pcisim::server {

// the fluoroscopy effects: "xray" (frames), "contrast" (injections show), "detector_noise"
struct XraySpec {
  xray::FluoroSpec fluoro;       // detector, projector, volume, noise, contrast strength
  double pulse_rate_fps = 15.0;  // fluoroscopy: 30, 15 or 7.5
  double cine_rate_fps = 30.0;   // cine runs
  xray::CArmPose initial_pose;   // until a session command moves the C-arm
  bool contrast = false;         // the scene lists "contrast"
  double injection_volume_ml = 8.0, injection_duration_s = 2.0;
  // the background beats with the heart (with vessel_motion only): phase bins per cycle, each
  // projected once per C-arm pose (0: the background stands still), blended per frame or not
  // (docs/benchmarks/xray-beating.md has the error and cost of each choice)
  int heart_phase_bins = 16;
  bool heart_phase_blend = true;
};

// the "ultrasound" effect: B-mode frames in the probe's plane through the deformed tissue
struct UltrasoundSpec {
  ultrasound::UsSettings settings;  // geometry, depth, gain, frequency, image size
  double frame_rate_hz = 20.0;      // [1, 60]
  uint32_t speckle_seed = 1;        // the tissue's speckle pattern
};

struct Scene {
  std::string name;
  std::string source;  // file path, or "built-in"
  // anatomy: a case folder (resolved against the scene file's folder), or "" for the procedural
  // phantom of world.anatomy.seed (server/case_builder.h builds the one anatomy::Case)
  std::string case_dir;
  // a procedural organ instead of the coronary phantom ("" or "kidney", seeded by
  // world.anatomy.seed): the soft-tissue scene's anatomy; "" with a case_dir (its organ is the case's)
  std::string organ;
  double physics_rate_hz = 30.0;
  physics::WorldSpec world;
  haptics::HapticParams haptics;
  std::optional<XraySpec> xray;              // present when the scene lists "xray"
  std::optional<UltrasoundSpec> ultrasound;  // present when the scene lists "ultrasound"
  SessionLimitParams session;                // bounds on console commands
  DebriefParams debrief;                     // what the session's debrief judges against
  std::vector<std::string> effects;          // the listed effects, in step order
};

// every effect name a scene may list, in the order the pipeline steps them
const std::vector<std::string>& known_effects();

// parse a scene; throws json::JsonError "<source>: <json path>: <what was expected>"
Scene parse_scene(const std::string& text, const std::string& source);
// refuses a file over kMaxSceneFileBytes before reading it
inline constexpr std::uintmax_t kMaxSceneFileBytes = 1 << 20;
Scene load_scene_file(const std::string& path);

// the built-in scene (the text of scenes/default.json, embedded at build time)
const std::string& default_scene_text();
Scene default_scene();

}  // namespace pcisim::server
