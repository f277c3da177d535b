#include "clients/bridge/device_profile.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "json/json_reader.h"
#include "json/regular_file.h"

namespace pcisim::clients {
namespace {

constexpr int64_t kMaxProfileBytes = 64 * 1024;

const char* const kDefaultProfile = R"({
  "name": "default",
  "insertion": {"mm_per_count": 0.01, "zero_counts": 0, "min_mm": 0, "max_mm": 400},
  "rotation": {"rad_per_count": 0.001},
  "silent_timeout_ms": 30,
  "force": {"axial_scale": 1, "torque_scale": 1, "max_axial_n": 20, "max_torque_nmm": 1000, "filter_hz": 0}
})";

// a non-zero scale in [-limit, limit]
double scale(json::JsonReader& r, const std::string& key, double fallback, double limit) {
  const double v = r.number(key, fallback, -limit, limit);
  if (v == 0.0)
    r.fail(key,
           fmt::format("expected a non-zero number in [{}, {}] (a negative one flips the sign), got 0", -limit, limit));
  return v;
}

}  // namespace

const std::string& default_device_profile_text() {
  static const std::string text = kDefaultProfile;
  return text;
}

DeviceProfile parse_device_profile(const std::string& text, const std::string& source) {
  DeviceProfile p;
  try {
    const nlohmann::json doc = json::parse_json_checked(text, source);
    json::JsonReader top(doc, "");
    p.name = top.text("name", p.name);
    {
      json::JsonReader r = top.child("insertion");
      SerialCalibration& c = p.calibration;
      c.mm_per_count = scale(r, "mm_per_count", c.mm_per_count, 1e3);
      c.insertion_zero_counts = static_cast<int64_t>(std::llround(r.number("zero_counts", 0, -1e12, 1e12)));
      c.min_insertion_mm = r.number("min_mm", c.min_insertion_mm, -2000, 2000);
      c.max_insertion_mm = r.number("max_mm", c.max_insertion_mm, -2000, 2000);
      if (c.max_insertion_mm < c.min_insertion_mm)
        r.fail("max_mm", fmt::format("expected at least min_mm ({}), got {}", c.min_insertion_mm, c.max_insertion_mm));
      r.finish();
    }
    {
      json::JsonReader r = top.child("rotation");
      p.calibration.rad_per_count = scale(r, "rad_per_count", p.calibration.rad_per_count, 10);
      r.finish();
    }
    p.calibration.silent_timeout_s = top.number("silent_timeout_ms", 30, 1, 50) * 1e-3;
    {
      json::JsonReader r = top.child("force");
      ForceShaping& f = p.force;
      f.axial_scale = scale(r, "axial_scale", f.axial_scale, kMaxForceScale);
      f.torque_scale = scale(r, "torque_scale", f.torque_scale, kMaxForceScale);
      f.max_axial_n = r.number("max_axial_n", f.max_axial_n, kMinForceLimit, kMaxAxialMilliNewton * 1e-3);
      f.max_torque_nmm =
          r.number("max_torque_nmm", f.max_torque_nmm, kMinForceLimit, kMaxTorqueMicroNewtonMetre * 1e-3);
      f.filter_hz = r.number("filter_hz", f.filter_hz, 0, kMaxFilterHz);
      if (f.filter_hz > 0 && f.filter_hz < kMinFilterHz)
        r.fail("filter_hz", fmt::format("expected 0 (no filter) or a cutoff in [1, 10000] Hz, got {}", f.filter_hz));
      r.finish();
    }
    top.finish();
  } catch (const json::JsonError& e) {
    throw std::runtime_error(fmt::format("{}: {}", source, e.what()));
  }
  validate(p.calibration);
  validate(p.force);
  return p;
}

void validate(const ForceShaping& f) {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("force shaping: ") + what);
  };
  auto scale_ok = [](double v) { return std::isfinite(v) && v != 0.0 && std::abs(v) <= kMaxForceScale; };
  require(scale_ok(f.axial_scale) && scale_ok(f.torque_scale), "scales must be finite, non-zero, within +-100");
  require(f.max_axial_n >= kMinForceLimit && f.max_axial_n <= kMaxAxialMilliNewton * 1e-3,
          "max_axial_n must be in [0.001, 20]");
  require(f.max_torque_nmm >= kMinForceLimit && f.max_torque_nmm <= kMaxTorqueMicroNewtonMetre * 1e-3,
          "max_torque_nmm must be in [0.001, 1000]");
  require(f.filter_hz == 0.0 || (f.filter_hz >= kMinFilterHz && f.filter_hz <= kMaxFilterHz),
          "filter_hz must be 0 or in [1, 10000]");
}

DeviceProfile load_device_profile(const std::string& path) {
  try {
    return parse_device_profile(json::read_regular_file(path, "the device profile", kMaxProfileBytes), path);
  } catch (const json::FileError& e) {
    throw std::runtime_error(e.what());
  }
}

// y += a (x - y) with a = 1 - exp(-2 pi f dt): the first-order low-pass, exact for a constant dt
ForceSetpoint ForceShaper::step(const ForceSetpoint& in, double dt_s, bool zero) {
  if (zero) {
    state_ = ForceSetpoint{};
    return state_;
  }
  // the stiffness scales with the force's magnitude (a flipped sign flips the force, not the spring)
  // and passes the filter unchanged
  const ForceSetpoint target{
      std::clamp(in.axial_n * shaping_.axial_scale, -shaping_.max_axial_n, shaping_.max_axial_n),
      std::clamp(in.torque_nmm * shaping_.torque_scale, -shaping_.max_torque_nmm, shaping_.max_torque_nmm),
      in.axial_stiffness_n_per_mm * std::abs(shaping_.axial_scale),
      in.torsional_stiffness_nmm_per_rad * std::abs(shaping_.torque_scale)};
  // no spring on an axis at the box's limit: it would push past it
  state_.sample_seq = in.sample_seq;
  state_.axial_stiffness_n_per_mm =
      std::abs(in.axial_n * shaping_.axial_scale) > shaping_.max_axial_n ? 0.0 : target.axial_stiffness_n_per_mm;
  state_.torsional_stiffness_nmm_per_rad = std::abs(in.torque_nmm * shaping_.torque_scale) > shaping_.max_torque_nmm
                                               ? 0.0
                                               : target.torsional_stiffness_nmm_per_rad;
  if (!(shaping_.filter_hz > 0.0)) {
    state_.axial_n = target.axial_n;
    state_.torque_nmm = target.torque_nmm;
    return state_;
  }
  const double a = 1.0 - std::exp(-2.0 * std::numbers::pi * shaping_.filter_hz * std::max(dt_s, 0.0));
  state_.axial_n += a * (target.axial_n - state_.axial_n);
  state_.torque_nmm += a * (target.torque_nmm - state_.torque_nmm);
  return state_;
}

}  // namespace pcisim::clients
