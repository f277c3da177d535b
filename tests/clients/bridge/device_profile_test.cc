// An instrument box's profile: the documented default, a full profile with flipped signs, every
// bad value refused naming the file and the JSON path; the force shaping's scale, limits and
// low-pass (its step response against 1 - e^(-2 pi f t)), zero in a fault sent at once; and the
// bridge handing its device the shaped force.
#include "clients/bridge/device_profile.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "clients/bridge/bridge.h"
#include "pcisim_lcm/force_command_t.hpp"
#include "protocol/channels.h"
#include "realtime/allocation_count.h"

namespace pcisim::clients {
namespace {

std::string error_of(const std::string& text) {
  try {
    parse_device_profile(text, "box.json");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(DeviceProfile, TheDefaultIsTheBridgesDefaults) {
  const DeviceProfile p = parse_device_profile(default_device_profile_text(), "default");
  const SerialCalibration c;
  EXPECT_EQ(p.calibration.mm_per_count, c.mm_per_count);
  EXPECT_EQ(p.calibration.rad_per_count, c.rad_per_count);
  EXPECT_EQ(p.calibration.max_insertion_mm, c.max_insertion_mm);
  EXPECT_DOUBLE_EQ(p.calibration.silent_timeout_s, c.silent_timeout_s);
  const ForceShaping f;
  EXPECT_EQ(p.force.axial_scale, f.axial_scale);
  EXPECT_EQ(p.force.max_axial_n, f.max_axial_n);
  EXPECT_EQ(p.force.filter_hz, f.filter_hz);
  // an empty object is the default too
  EXPECT_EQ(parse_device_profile("{}", "empty").calibration.mm_per_count, c.mm_per_count);
}

TEST(DeviceProfile, AFullProfileWithFlippedSigns) {
  const DeviceProfile p = parse_device_profile(R"({
    "name": "bench box v2",
    "insertion": {"mm_per_count": -0.005, "zero_counts": 1200, "min_mm": 0, "max_mm": 250},
    "rotation": {"rad_per_count": -0.002},
    "silent_timeout_ms": 20,
    "force": {"axial_scale": -0.5, "torque_scale": 2, "max_axial_n": 3, "max_torque_nmm": 40, "filter_hz": 100}
  })",
                                               "box.json");
  EXPECT_EQ(p.name, "bench box v2");
  EXPECT_EQ(p.calibration.mm_per_count, -0.005);
  EXPECT_EQ(p.calibration.insertion_zero_counts, 1200);
  EXPECT_EQ(p.calibration.max_insertion_mm, 250);
  EXPECT_EQ(p.calibration.rad_per_count, -0.002);
  EXPECT_DOUBLE_EQ(p.calibration.silent_timeout_s, 0.020);
  EXPECT_EQ(p.force.axial_scale, -0.5);
  EXPECT_EQ(p.force.torque_scale, 2);
  EXPECT_EQ(p.force.max_axial_n, 3);
  EXPECT_EQ(p.force.max_torque_nmm, 40);
  EXPECT_EQ(p.force.filter_hz, 100);
}

TEST(DeviceProfile, EachBadValueIsRefusedNamingTheFileAndTheField) {
  EXPECT_EQ(error_of(R"({"force": {"max_axial_n": 50}})"),
            "box.json: force.max_axial_n: expected a number in [0.001, 20], got 50");
  EXPECT_EQ(error_of(R"({"insertion": {"mm_per_count": 0}})"),
            "box.json: insertion.mm_per_count: expected a non-zero number in [-1000, 1000] (a negative one flips "
            "the sign), got 0");
  EXPECT_EQ(error_of(R"({"force": {"filter_hz": 0.5}})"),
            "box.json: force.filter_hz: expected 0 (no filter) or a cutoff in [1, 10000] Hz, got 0.5");
  EXPECT_EQ(error_of(R"({"insertion": {"min_mm": 10, "max_mm": 5}})"),
            "box.json: insertion.max_mm: expected at least min_mm (10), got 5");
  EXPECT_EQ(error_of(R"({"silent_timeout_ms": 80})"),
            "box.json: silent_timeout_ms: expected a number in [1, 50], got 80");
  const std::string unknown = error_of(R"({"force": {"gain": 2}})");
  EXPECT_EQ(unknown.rfind("box.json: force.gain: unknown key", 0), 0u) << unknown;
  const std::string syntax = error_of(R"({"force": )");
  EXPECT_EQ(syntax.rfind("box.json", 0), 0u) << syntax;
  EXPECT_THROW(load_device_profile("/no/such/profile.json"), std::runtime_error);
}

// a device that keeps what it is asked to render
struct RecordingDevice : InstrumentDevice {
  std::mutex mutex;
  std::vector<ForceSetpoint> rendered;
  bool read(double, InstrumentReading& out) override {
    out = InstrumentReading{};
    return true;
  }
  bool render(const ForceSetpoint& f, int64_t) override {
    std::lock_guard lock(mutex);
    if (rendered.size() < rendered.capacity()) rendered.push_back(f);
    return true;
  }
  std::string describe() const override { return "recording"; }
};

TEST(ForceShaper, ABridgeRefusesShapingSetInCodeThatTheProfileWouldRefuse) {
  lcm::LCM lcm("memq://");
  RecordingDevice device;
  for (void (*bad)(ForceShaping&) :
       {+[](ForceShaping& f) { f.max_axial_n = 0.0; }, +[](ForceShaping& f) { f.axial_scale = std::nan(""); },
        +[](ForceShaping& f) { f.torque_scale = 0.0; }, +[](ForceShaping& f) { f.filter_hz = 0.5; }}) {
    BridgeOptions o;
    bad(o.force_shaping);
    EXPECT_THROW(Bridge(lcm, device, o), std::invalid_argument);
  }
}

TEST(ForceShaper, ScalesClampsFiltersAndZeroesAtOnce) {
  ForceShaping s;
  s.axial_scale = -2.0;
  s.torque_scale = 0.5;
  s.max_axial_n = 1.0;
  ForceShaper unfiltered(s);
  ForceSetpoint out = unfiltered.step({0.3, 4.0}, 1e-3, false);
  EXPECT_DOUBLE_EQ(out.axial_n, -0.6);
  EXPECT_DOUBLE_EQ(out.torque_nmm, 2.0);
  EXPECT_DOUBLE_EQ(unfiltered.step({3.0, 0.0}, 1e-3, false).axial_n, -1.0) << "clamped to the box's limit";
  // a 50 Hz low-pass answers a step with 1 - e^(-2 pi f t)
  s = ForceShaping{};
  s.filter_hz = 50.0;
  ForceShaper filtered(s);
  realtime::AllocationCount count;
  double y = 0.0;
  for (int k = 1; k <= 10; ++k) y = filtered.step({1.0, 0.0}, 1e-3, false).axial_n;
  EXPECT_EQ(count.allocations(), 0);
  EXPECT_NEAR(y, 1.0 - std::exp(-2.0 * std::numbers::pi * 50.0 * 0.010), 1e-12);
  // a fault: zero at once, not faded through the filter, and the filter starts again from zero
  out = filtered.step({1.0, 1.0}, 1e-3, true);
  EXPECT_EQ(out.axial_n, 0.0);
  EXPECT_EQ(out.torque_nmm, 0.0);
  EXPECT_NEAR(filtered.step({1.0, 0.0}, 1e-3, false).axial_n, 1.0 - std::exp(-2.0 * std::numbers::pi * 50.0 * 1e-3),
              1e-12);
}

// the stiffness scales with the force's magnitude (a flipped sign flips the force, not the
// spring), passes the filter unchanged, is gone on an axis at the limit and in a fault
TEST(ForceShaper, ScalesTheStiffnessByTheScalesMagnitudeAndDropsItAtTheLimit) {
  ForceShaping s;
  s.torque_scale = -2.0;
  s.max_torque_nmm = 10.0;
  s.filter_hz = 50.0;
  ForceShaper shaper(s);
  ForceSetpoint in;
  in.torque_nmm = 1.0;
  in.torsional_stiffness_nmm_per_rad = 3.0;
  in.axial_stiffness_n_per_mm = 0.5;
  in.sample_seq = 12;
  ForceSetpoint out = shaper.step(in, 1e-3, false);
  EXPECT_DOUBLE_EQ(out.torsional_stiffness_nmm_per_rad, 6.0);
  EXPECT_DOUBLE_EQ(out.axial_stiffness_n_per_mm, 0.5);
  EXPECT_EQ(out.sample_seq, 12);
  EXPECT_LT(out.torque_nmm, 0.0) << "the torque flipped";
  EXPECT_GT(out.torque_nmm, -2.0) << "and filtered";
  in.torque_nmm = 6.0;  // 12 N mm after the scale: past the 10 N mm limit
  out = shaper.step(in, 1e-3, false);
  EXPECT_EQ(out.torsional_stiffness_nmm_per_rad, 0.0);
  EXPECT_DOUBLE_EQ(out.axial_stiffness_n_per_mm, 0.5);
  out = shaper.step(in, 1e-3, true);
  EXPECT_EQ(out.torsional_stiffness_nmm_per_rad, 0.0);
  EXPECT_EQ(out.axial_stiffness_n_per_mm, 0.0);
  EXPECT_EQ(out.sample_seq, -1);
}

TEST(ForceShaper, TheBridgeHandsItsDeviceTheShapedForce) {
  lcm::LCM lcm("memq://");
  RecordingDevice device;
  device.rendered.reserve(1000);
  BridgeOptions o;
  o.duration_s = 0.2;
  o.log_each_second = false;
  o.force_shaping.axial_scale = -0.5;
  o.force_shaping.max_torque_nmm = 3.0;
  Bridge bridge(lcm, device, o);
  std::atomic<bool> done{false};
  std::thread server([&] {
    pcisim_lcm::force_command_t m{};
    m.axial_force_n = 0.8;
    m.torque_nmm = 10.0;
    while (!done) {
      lcm.publish(protocol::kForceChannel, &m);
      usleep(1000);
    }
  });
  std::atomic<bool> stop{false};
  bridge.run(stop);
  done = true;
  server.join();
  std::lock_guard lock(device.mutex);
  ASSERT_GT(device.rendered.size(), 100u);
  // what was rendered is the shaped force or, while no fresh command was there, zero: nothing else
  int shaped = 0;
  for (const ForceSetpoint& f : device.rendered) {
    if (f.axial_n == 0.0 && f.torque_nmm == 0.0) continue;
    EXPECT_DOUBLE_EQ(f.axial_n, -0.4);    // 0.8 N x -0.5
    EXPECT_DOUBLE_EQ(f.torque_nmm, 3.0);  // 10 N mm clamped to 3
    ++shaped;
  }
  EXPECT_GT(shaped, static_cast<int>(device.rendered.size()) / 2);
}

}  // namespace
}  // namespace pcisim::clients
