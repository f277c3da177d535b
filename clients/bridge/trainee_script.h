#pragma once
// A scripted trainee: timed insert / pull / rotate / pedal / contrast actions (JSON, format in
// docs/trainee-script.md), sampled at any time as the instrument would report it.
#include <cstdint>
#include <string>
#include <vector>

namespace pcisim::clients {

struct InstrumentReading {
  double insertion_mm = 0, rotation_rad = 0;
  double insertion_rate_mm_s = 0, rotation_rate_rad_s = 0;
  int32_t buttons = 0;  // instrument_state_t::BUTTON_* bits
};

// a trainee script is a page of JSON; a larger file is refused unread
inline constexpr int64_t kMaxScriptFileBytes = int64_t{1} << 20;

class TraineeScript {
 public:
  // throws std::runtime_error naming the source and the JSON path of a bad action
  static TraineeScript parse(const std::string& text, const std::string& source);
  static TraineeScript load(const std::string& path);
  static const std::string& builtin_text();  // the main job's trainee

  InstrumentReading sample(double t_s) const;
  double duration_s() const { return duration_s_; }
  const std::string& name() const { return name_; }

 private:
  struct Ramp {
    double start_s, duration_s, delta;  // axis value moves by delta over [start, start+duration]
  };
  struct Hold {
    double start_s, end_s;
    int32_t bit;
  };
  static double value(const std::vector<Ramp>& ramps, double t_s, double* rate);

  std::string name_;
  std::vector<Ramp> insertion_mm_, rotation_rad_;
  std::vector<Hold> buttons_;
  double duration_s_ = 0;
};

}  // namespace pcisim::clients
