#include "clients/bridge/trainee_script.h"

#include <algorithm>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "pcisim_lcm/instrument_state_t.hpp"
#include "json/json_reader.h"
#include "json/regular_file.h"

namespace pcisim::clients {
namespace {

using json::JsonError;
using json::JsonReader;
constexpr double kInf = std::numeric_limits<double>::infinity();

// the main job's trainee: engage the LM, steer the angled tip toward the LAD and advance
const char* kBuiltin =
    R"json(// built-in trainee: into the left main, turn toward the LAD, advance under fluoroscopy with two
// contrast puffs (one as the wire leaves the left main, one with the wire in the LAD)
{
  "name": "lad-approach",
  "actions": [
    {"at_s": 0.5, "do": "insert", "mm": 8, "over_s": 3},
    {"at_s": 4.0, "do": "rotate", "deg": 90, "over_s": 2},
    {"at_s": 6.5, "do": "pedal", "down": true},
    {"at_s": 7.0, "do": "contrast", "for_s": 2},
    {"at_s": 7.0, "do": "insert", "mm": 44, "over_s": 10},
    {"at_s": 13.0, "do": "contrast", "for_s": 2},
    {"at_s": 17.5, "do": "pull", "mm": 5, "over_s": 1},
    {"at_s": 19.0, "do": "pedal", "down": false}
  ]
}
)json";

}  // namespace

const std::string& TraineeScript::builtin_text() {
  static const std::string text = kBuiltin;
  return text;
}

TraineeScript TraineeScript::parse(const std::string& text, const std::string& source) {
  TraineeScript s;
  nlohmann::json doc;
  try {
    doc = json::parse_json_checked(text, source);
  } catch (const json::JsonError& e) {
    throw std::runtime_error(e.what());
  }
  try {
    JsonReader top(doc, "");
    s.name_ = top.text("name", "unnamed");
    const auto& actions = top.list("actions");
    top.finish();
    if (actions.empty()) top.fail("actions", "expected at least one action");
    for (size_t i = 0; i < actions.size(); ++i) {
      JsonReader a(actions[i], fmt::format("actions[{}]", i));
      const double at_s = a.number("at_s", 0, 0, 1e6);
      const std::string what = a.text("do", "", {"insert", "pull", "rotate", "pedal", "cine", "contrast"});
      if (what.empty()) a.fail("do", "expected one of insert, pull, rotate, pedal, cine, contrast");
      double end_s = at_s;
      if (what == "insert" || what == "pull") {
        const double mm = a.number("mm", 0, -1000, 1000);
        const double over_s = a.number("over_s", 1, 1e-3, 1e5);
        s.insertion_mm_.push_back({at_s, over_s, what == "pull" ? -mm : mm});
        end_s = at_s + over_s;
      } else if (what == "rotate") {
        const double deg = a.number("deg", 0, -1e6, 1e6);
        const double over_s = a.number("over_s", 1, 1e-3, 1e5);
        s.rotation_rad_.push_back({at_s, over_s, deg * std::numbers::pi / 180.0});
        end_s = at_s + over_s;
      } else if (what == "pedal" || what == "cine") {
        const bool down = a.boolean("down", true);
        const int32_t bit = what == "pedal" ? int32_t{pcisim_lcm::instrument_state_t::BUTTON_FLUORO_PEDAL}
                                            : int32_t{pcisim_lcm::instrument_state_t::BUTTON_CINE_PEDAL};
        // a press opens a hold that the next release of the same pedal closes
        if (down) {
          s.buttons_.push_back({at_s, kInf, bit});
        } else {
          for (auto& h : s.buttons_)
            if (h.bit == bit && h.end_s == kInf) h.end_s = at_s;
        }
      } else {  // contrast
        const double for_s = a.number("for_s", 2, 0.1, 60);
        s.buttons_.push_back({at_s, at_s + for_s, pcisim_lcm::instrument_state_t::BUTTON_CONTRAST});
        end_s = at_s + for_s;
      }
      a.finish();
      s.duration_s_ = std::max(s.duration_s_, end_s);
    }
  } catch (const json::JsonError& e) {
    throw std::runtime_error(fmt::format("{}: {}", source, e.what()));
  }
  return s;
}

TraineeScript TraineeScript::load(const std::string& path) {
  // a regular file of at most a MiB (a FIFO or /dev/zero named as a script would hang the reader)
  try {
    return parse(json::read_regular_file(path, "the trainee script", kMaxScriptFileBytes), path);
  } catch (const json::FileError& e) {
    throw std::runtime_error(e.what());
  }
}

double TraineeScript::value(const std::vector<Ramp>& ramps, double t_s, double* rate) {
  double v = 0;
  *rate = 0;
  for (const auto& r : ramps) {
    const double u = (t_s - r.start_s) / r.duration_s;
    v += r.delta * std::clamp(u, 0.0, 1.0);
    if (u >= 0 && u < 1) *rate += r.delta / r.duration_s;
  }
  return v;
}

InstrumentReading TraineeScript::sample(double t_s) const {
  InstrumentReading r;
  r.insertion_mm = value(insertion_mm_, t_s, &r.insertion_rate_mm_s);
  r.rotation_rad = value(rotation_rad_, t_s, &r.rotation_rate_rad_s);
  for (const auto& h : buttons_)
    if (t_s >= h.start_s && t_s < h.end_s) r.buttons |= h.bit;
  return r;
}

}  // namespace pcisim::clients
