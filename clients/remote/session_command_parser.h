#pragma once
// Turns a page's JSON command into a session_command_t, or says why not. Only the commands a
// remote page may give are known here: loading a scene names a file on the server's host and is
// left to the local console. Ranges follow what the server accepts (server/lcm_io.cc, scenes).
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <variant>

#include "pcisim_lcm/session_command_t.hpp"

namespace pcisim::remote {

struct CommandLimits {
  double primary_abs_deg = 180;                        // the server ignores |primary| > 180
  double secondary_abs_deg = 90;                       // and |secondary| > 90
  double contrast_ml_min = 0.5, contrast_ml_max = 30;  // a scene's injection_ml range
  double contrast_ml_s_min = 0.5, contrast_ml_s_max = 20;
  double default_contrast_ml = 8, default_contrast_ml_s = 4;
};

struct CommandError {
  std::string code;     // "bad_command", "out_of_range"
  std::string message;  // for the person at the page
};

using ParsedCommand = std::variant<pcisim_lcm::session_command_t, CommandError>;

// `msg` is the whole {"type":"command", "command": ...} object
ParsedCommand parse_session_command(const nlohmann::json& msg, const CommandLimits& limits);

}  // namespace pcisim::remote
