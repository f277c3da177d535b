#include "clients/bridge/probe_script.h"
#include "clients/bridge/trainee_script.h"  // kMaxScriptFileBytes

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "pcisim_lcm/probe_state_t.hpp"
#include "protocol/probe_ranges.h"
#include "json/json_reader.h"
#include "json/regular_file.h"

namespace pcisim::clients {
namespace {

using json::JsonReader;
using protocol::kProbeMaxDepthMm;
using protocol::kProbeMaxDistanceMm;
using protocol::kProbeMaxGainDb;
using protocol::kProbeMinDepthMm;

constexpr double kMaxTimeS = 1e6;
// below this a quaternion is a typo, not a direction to normalise
constexpr double kMinQuaternionNorm = 1e-6;

// the main job's probe on the kidney phantom (anatomy/organ/kidney_phantom.h: organ frame LPS, mm,
// centre at the origin, semi-axes 30 x 17.5 x 55 mm; supine, so the anterior skin is at y = -17.5).
// Orientation: -90 deg about x alone, [cos(-45), sin(-45), 0, 0], does map the beam (probe z) to
// +y (Eigen: (0, 1, -2e-16)) but leaves the lateral axis (probe x) on scene x (L), across the organ.
// So -90 deg about z first, then -90 deg about x: q = q_x(-90) q_z(-90) = [0.5, -0.5, -0.5, -0.5]
// (-120 deg about (1, 1, 1)/sqrt(3)), which Eigen gives as beam -> (0, 1, 0) (posterior, into the
// organ), lateral -> (0, 0, 1) (S, the long axis), probe y -> (1, 0, 0) (probe_script_test.cc
// checks it). The tilted keyframe is that pose turned 15 deg about probe y (the axis across the
// image plane): the beam leans toward +z, (0, cos 15, sin 15).
const char* kBuiltin =
    R"json(// built-in probe: from 5 mm above the kidney's anterior skin, press 8 mm in, then image 80 mm
// deep with 6 dB more gain (from 3.5 s until the probe is back up at 9 s), slide 15 mm toward the
// head while pressed, rock 15 deg and back, withdraw
{
  "name": "kidney-press",
  "keyframes": [
    {"t_s": 0.0, "position_mm": [0, -22.5, 0], "orientation_wxyz": [0.5, -0.5, -0.5, -0.5]},
    {"t_s": 0.5, "position_mm": [0, -22.5, 0], "orientation_wxyz": [0.5, -0.5, -0.5, -0.5]},
    {"t_s": 2.5, "position_mm": [0, -9.5, 0], "orientation_wxyz": [0.5, -0.5, -0.5, -0.5]},
    {"t_s": 3.5, "position_mm": [0, -9.5, 0], "orientation_wxyz": [0.5, -0.5, -0.5, -0.5],
     "depth_mm": 80, "gain_db": 6},
    {"t_s": 5.5, "position_mm": [0, -9.5, 15], "orientation_wxyz": [0.5, -0.5, -0.5, -0.5]},
    {"t_s": 6.5, "position_mm": [0, -9.5, 15],
     "orientation_wxyz": [0.5609855268, -0.4304593346, -0.4304593346, -0.5609855268]},
    {"t_s": 7.5, "position_mm": [0, -9.5, 15], "orientation_wxyz": [0.5, -0.5, -0.5, -0.5]},
    {"t_s": 9.0, "position_mm": [0, -22.5, 15], "orientation_wxyz": [0.5, -0.5, -0.5, -0.5],
     "depth_mm": 0, "gain_db": 0},
    {"t_s": 10.0, "position_mm": [0, -22.5, 15], "orientation_wxyz": [0.5, -0.5, -0.5, -0.5]}
  ]
}
)json";

// a list of N finite numbers under `key`; fails with `expected` otherwise
template <size_t N>
std::array<double, N> read_numbers(JsonReader& r, const nlohmann::json& object, const std::string& key,
                                   const std::string& expected) {
  if (!r.has(key)) r.fail(key, expected + " (required)");
  std::array<double, N> out{};
  if (!r.numbers(key, out)) r.fail(key, fmt::format("{}, got {}", expected, json::short_dump(object.at(key))));
  return out;
}

}  // namespace

const std::string& ProbeScript::builtin_text() {
  static const std::string text = kBuiltin;
  return text;
}

ProbeScript ProbeScript::parse(const std::string& text, const std::string& source) {
  ProbeScript s;
  nlohmann::json doc;
  try {
    doc = json::parse_json_checked(text, source);
  } catch (const json::JsonError& e) {
    throw std::runtime_error(e.what());
  }
  try {
    JsonReader top(doc, "");
    s.name_ = top.text("name", "unnamed");
    const auto& keyframes = top.list("keyframes");
    top.finish();
    if (keyframes.empty()) top.fail("keyframes", "expected at least one keyframe");
    s.keyframes_.reserve(keyframes.size());
    ProbeReading held;  // depth, gain and freeze carry over from the keyframe before
    for (size_t i = 0; i < keyframes.size(); ++i) {
      JsonReader k(keyframes[i], fmt::format("keyframes[{}]", i));
      const auto& object = keyframes[i];
      if (!k.has("t_s")) k.fail("t_s", fmt::format("expected a time in [0, {}] s (required)", kMaxTimeS));
      const double t_s = k.number("t_s", 0, 0, kMaxTimeS);
      if (i > 0 && !(t_s > s.keyframes_.back().t_s))
        k.fail("t_s",
               fmt::format("expected a time after the previous keyframe's {} s, got {}", s.keyframes_.back().t_s, t_s));

      // the decoder's ranges (protocol/probe_ranges.h), refused here with the key's path
      ProbeReading r = held;
      r.position_mm = read_numbers<3>(
          k, object, "position_mm",
          fmt::format("expected [x, y, z] in mm within {} mm of the scene's origin", kProbeMaxDistanceMm));
      if (!protocol::is_probe_position_mm(r.position_mm[0], r.position_mm[1], r.position_mm[2]))
        k.fail("position_mm", fmt::format("expected [x, y, z] in mm within {} mm of the scene's origin, got {}",
                                          kProbeMaxDistanceMm, json::short_dump(object.at("position_mm"))));

      const std::string q_expected = fmt::format(
          "expected [w, x, y, z], a finite quaternion of norm at least {} (normalised on read)", kMinQuaternionNorm);
      const auto q = read_numbers<4>(k, object, "orientation_wxyz", q_expected);
      const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
      if (!std::isfinite(norm) || norm < kMinQuaternionNorm)
        k.fail("orientation_wxyz",
               fmt::format("{}, got {}", q_expected, json::short_dump(object.at("orientation_wxyz"))));
      for (size_t c = 0; c < 4; ++c) r.orientation_wxyz[c] = q[c] / norm;

      r.depth_mm = k.number("depth_mm", held.depth_mm, 0, kProbeMaxDepthMm);
      if (!protocol::is_probe_depth_mm(r.depth_mm))
        k.fail("depth_mm", fmt::format("expected 0 (the scene's depth) or a depth in [{}, {}] mm, got {}",
                                       kProbeMinDepthMm, kProbeMaxDepthMm, r.depth_mm));
      r.gain_db = k.number("gain_db", held.gain_db, -kProbeMaxGainDb, kProbeMaxGainDb);
      const bool freeze = k.boolean("freeze", (held.buttons & pcisim_lcm::probe_state_t::BUTTON_FREEZE) != 0);
      r.buttons = freeze ? pcisim_lcm::probe_state_t::BUTTON_FREEZE : 0;
      k.finish();
      s.keyframes_.push_back({t_s, r});
      held = r;
    }
  } catch (const json::JsonError& e) {
    throw std::runtime_error(fmt::format("{}: {}", source, e.what()));
  }
  return s;
}

ProbeScript ProbeScript::load(const std::string& path) {
  // a regular file of at most a MiB (a FIFO or /dev/zero named as a script would hang the reader)
  try {
    return parse(json::read_regular_file(path, "the probe script", kMaxScriptFileBytes), path);
  } catch (const json::FileError& e) {
    throw std::runtime_error(e.what());
  }
}

ProbeReading ProbeScript::sample(double t_s) const {
  // the first keyframe after t_s (a NaN time finds none: the last keyframe holds)
  const auto next = std::upper_bound(keyframes_.begin(), keyframes_.end(), t_s,
                                     [](double t, const Keyframe& k) { return t < k.t_s; });
  if (next == keyframes_.begin()) return keyframes_.front().reading;
  if (next == keyframes_.end()) return keyframes_.back().reading;
  const Keyframe& a = *(next - 1);
  const Keyframe& b = *next;
  const double u = (t_s - a.t_s) / (b.t_s - a.t_s);
  ProbeReading r = a.reading;  // depth, gain and buttons step at their keyframe
  for (size_t c = 0; c < 3; ++c)
    r.position_mm[c] = a.reading.position_mm[c] + u * (b.reading.position_mm[c] - a.reading.position_mm[c]);
  const auto& qa = a.reading.orientation_wxyz;
  const auto& qb = b.reading.orientation_wxyz;
  // slerp takes the shorter arc (q and -q are one pose)
  const Eigen::Quaterniond q =
      Eigen::Quaterniond(qa[0], qa[1], qa[2], qa[3]).slerp(u, Eigen::Quaterniond(qb[0], qb[1], qb[2], qb[3]));
  r.orientation_wxyz = {q.w(), q.x(), q.y(), q.z()};
  return r;
}

}  // namespace pcisim::clients
