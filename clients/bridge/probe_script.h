#pragma once
// A scripted ultrasound probe: timed keyframes of its 6-DOF pose, imaging depth, gain and freeze
// button (JSON, format in docs/trainee-script.md, "Probe script"), sampled at any time as
// probe_state_t would report it.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace pcisim::clients {

struct ProbeReading {
  std::array<double, 3> position_mm{};                 // centre of the probe's face, scene frame
  std::array<double, 4> orientation_wxyz{1, 0, 0, 0};  // unit quaternion, probe frame to scene frame
  double depth_mm = 0;                                 // 0: the scene's
  double gain_db = 0;
  int32_t buttons = 0;  // probe_state_t::BUTTON_* bits
};

class ProbeScript {
 public:
  // throws std::runtime_error naming the source and the JSON path of a bad keyframe
  static ProbeScript parse(const std::string& text, const std::string& source);
  static ProbeScript load(const std::string& path);
  static const std::string& builtin_text();  // the main job's probe: a press on the kidney phantom

  // position linear and orientation slerp between keyframes; depth, gain and freeze step at their
  // keyframe; the first keyframe before it, the last after it. Allocates nothing.
  ProbeReading sample(double t_s) const;
  double duration_s() const { return keyframes_.back().t_s; }
  const std::string& name() const { return name_; }

 private:
  struct Keyframe {
    double t_s;
    ProbeReading reading;
  };
  ProbeScript() = default;

  std::string name_;
  std::vector<Keyframe> keyframes_;  // at least one, times strictly increasing
};

}  // namespace pcisim::clients
