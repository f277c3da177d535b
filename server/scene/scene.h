#pragma once
// A scene: anatomy, instrument limits and the list of effects with their parameters.
// The server builds exactly the listed effects.
#include <string>
#include <vector>

#include "haptics/haptic_params.h"
#include "physics/world_spec.h"

namespace pcisim::server {

struct Scene {
  std::string name;
  std::string source;                 // file path, or "built-in"
  double physics_rate_hz = 30.0;
  physics::WorldSpec world;
  haptics::HapticParams haptics;
  std::vector<std::string> effects;   // the listed effects, in step order
};

// every effect name a scene may list, in the order the pipeline steps them
const std::vector<std::string>& known_effects();

// parse a scene; throws SceneError "<source>: <json path>: <what was expected>"
Scene parse_scene(const std::string& text, const std::string& source);
Scene load_scene_file(const std::string& path);

// the built-in scene (the text of scenes/default.json, embedded at build time)
const std::string& default_scene_text();
Scene default_scene();

}  // namespace pcisim::server
