#include "clients/remote/session_command_parser.h"

#include <cmath>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace pcisim::remote {

namespace {

using C = pcisim_lcm::session_command_t;

// a finite number in [lo, hi]; json's own conversions would accept strings and booleans
bool number_in(const nlohmann::json& msg, const char* key, double lo, double hi, double& out, CommandError& err) {
  const auto it = msg.find(key);
  if (it == msg.end() || !it->is_number()) {
    err = {"bad_command", fmt::format("'{}' must be a number", key)};
    return false;
  }
  out = it->get<double>();
  if (!std::isfinite(out) || out < lo || out > hi) {
    err = {"out_of_range", fmt::format("'{}' must lie in [{}, {}]", key, lo, hi)};
    return false;
  }
  return true;
}

}  // namespace

ParsedCommand parse_session_command(const nlohmann::json& msg, const CommandLimits& limits) {
  if (!msg.is_object() || !msg.contains("command") || !msg["command"].is_string())
    return CommandError{"bad_command", "a command needs a 'command' string"};
  const std::string name = msg["command"].get<std::string>();
  C c{};
  CommandError err;
  if (name == "fluoro" || name == "cine") {
    const auto it = msg.find("down");
    if (it == msg.end() || !it->is_boolean()) return CommandError{"bad_command", "'down' must be true or false"};
    c.command = name == "fluoro" ? C::CMD_FLUORO_PEDAL : C::CMD_CINE;
    c.pedal_down = it->get<bool>() ? 1 : 0;
  } else if (name == "carm") {
    if (!number_in(msg, "primary_deg", -limits.primary_abs_deg, limits.primary_abs_deg, c.primary_angle_deg, err) ||
        !number_in(msg, "secondary_deg", -limits.secondary_abs_deg, limits.secondary_abs_deg, c.secondary_angle_deg,
                   err))
      return err;
    c.command = C::CMD_CARM;
  } else if (name == "contrast") {
    c.command = C::CMD_CONTRAST;
    c.contrast_ml = limits.default_contrast_ml;
    c.contrast_ml_s = limits.default_contrast_ml_s;
    if (msg.contains("ml") && !number_in(msg, "ml", limits.contrast_ml_min, limits.contrast_ml_max, c.contrast_ml, err))
      return err;
    if (msg.contains("ml_s") &&
        !number_in(msg, "ml_s", limits.contrast_ml_s_min, limits.contrast_ml_s_max, c.contrast_ml_s, err))
      return err;
  } else if (name == "reset") {
    c.command = C::CMD_RESET;
  } else if (name == "pause") {
    c.command = C::CMD_PAUSE;
  } else if (name == "resume") {
    c.command = C::CMD_RESUME;
  } else if (name == "debrief") {
    c.command = C::CMD_DEBRIEF;
  } else {
    return CommandError{"bad_command", fmt::format("unknown or not permitted command '{}'", name)};
  }
  return c;
}

}  // namespace pcisim::remote
