// A Linux force-feedback device as the instrument (issue #37 part 2): its settings and names are
// checked everywhere; the device itself against a wheel made by the kernel's uinput module (no
// hardware), where the kernel offers one: axes and pedals read, the torque rendered as one
// constant effect updated in place, stopped at zero (every fault sends zero), erased on exit,
// the gain set and the device's own centring spring turned off; an unplugged wheel faults.
#include <gtest/gtest.h>

#include <linux/input.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <numbers>
#include <thread>

#include "clients/bridge/bridge.h"
#include "clients/bridge/evdev_device.h"
#include "pcisim_lcm/force_command_t.hpp"
#include "protocol/channels.h"
#include "realtime/clock.h"
#include "tests/clients/bridge/uinput_wheel.h"
#include "realtime/allocation_count.h"

namespace pcisim::clients {
namespace {

using testing::FfRecord;
using testing::UinputWheel;

TEST(EvdevConfig, NamesAndBadSettingsAreRefusedByName) {
  EXPECT_EQ(evdev_axis_code("ABS_X"), ABS_X);
  EXPECT_EQ(evdev_axis_code("ABS_GAS"), ABS_GAS);
  EXPECT_EQ(evdev_axis_code("5"), 5);
  EXPECT_EQ(evdev_axis_code("ABS_NOPE"), -1);
  EXPECT_EQ(evdev_axis_code("64"), -1) << "beyond ABS_MAX";
  EXPECT_EQ(evdev_key_code("BTN_TRIGGER"), BTN_TRIGGER);
  EXPECT_EQ(evdev_key_code("none"), -1);
  EXPECT_EQ(evdev_key_code("x1"), -1);
  EXPECT_NO_THROW(validate(EvdevConfig{}));
  const std::pair<const char*, void (*)(EvdevConfig&)> cases[] = {
      {"two different axes", [](EvdevConfig& c) { c.rotation_axis = c.insertion_axis; }},
      {"insertion range", [](EvdevConfig& c) { c.max_insertion_mm = c.min_insertion_mm; }},
      {"wheel_range_deg", [](EvdevConfig& c) { c.wheel_range_deg = 0.0; }},
      {"wheel_range_deg", [](EvdevConfig& c) { c.wheel_range_deg = NAN; }},
      {"full_scale_torque_nmm", [](EvdevConfig& c) { c.full_scale_torque_nmm = -1.0; }},
      {"gain", [](EvdevConfig& c) { c.gain = 1.5; }},
      {"key", [](EvdevConfig& c) { c.cine_key = KEY_CNT; }},
      {"insertion axis", [](EvdevConfig& c) { c.insertion_axis = ABS_CNT; }},
  };
  for (const auto& [what, spoil] : cases) {
    EvdevConfig c;
    spoil(c);
    try {
      validate(c);
      ADD_FAILURE() << what << ": accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }
}

TEST(EvdevConfig, TheLevelIsTheTorqueOverTheFullScaleRoundedAndClamped) {
  EXPECT_EQ(constant_level(10.0, 20.0), 16384);  // 0.5 * 32767 = 16383.5, rounded away from zero
  EXPECT_EQ(constant_level(-10.0, 20.0), -16384);
  EXPECT_EQ(constant_level(20.0, 20.0), 32767);
  EXPECT_EQ(constant_level(1e9, 20.0), 32767);
  EXPECT_EQ(constant_level(-1e9, 20.0), -32767);
  EXPECT_EQ(constant_level(NAN, 20.0), 0);
  EXPECT_EQ(constant_level(1e-6, 20.0), 0);
}

TEST(EvdevDevice, ANodeThatIsNoEventDeviceIsRefusedByName) {
  EXPECT_THROW(
      {
        try {
          EvdevDevice d("/nonexistent/event7", EvdevConfig{});
        } catch (const std::runtime_error& e) {
          EXPECT_NE(std::string(e.what()).find("/nonexistent/event7"), std::string::npos) << e.what();
          throw;
        }
      },
      std::runtime_error);
  EXPECT_THROW(EvdevDevice("/dev/null", EvdevConfig{}), std::runtime_error);
}

class UinputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string why = UinputWheel::unavailable();
    if (!why.empty()) GTEST_SKIP() << why;
  }
  // the records of one kind
  static std::vector<FfRecord> of(const std::vector<FfRecord>& all, FfRecord::Kind kind) {
    std::vector<FfRecord> out;
    for (const FfRecord& r : all)
      if (r.kind == kind) out.push_back(r);
    return out;
  }
  // waits up to 1 s for the serving thread to have recorded n of a kind
  static std::vector<FfRecord> wait_for(const UinputWheel& w, FfRecord::Kind kind, size_t n) {
    for (int i = 0; i < 200 && of(w.records(), kind).size() < n; ++i) usleep(5000);
    return of(w.records(), kind);
  }
};

TEST_F(UinputTest, ReadsTheAxesAndPedalsAsTheConfigMapsThem) {
  UinputWheel wheel;
  EvdevConfig cfg;
  cfg.min_insertion_mm = 0.0;
  cfg.max_insertion_mm = 200.0;
  cfg.wheel_range_deg = 900.0;
  EvdevDevice dev(wheel.event_path(), cfg);
  InstrumentReading r;
  ASSERT_TRUE(dev.read(0.0, r));
  wheel.move(ABS_Y, 1023);   // the pedal down: the whole insertion
  wheel.move(ABS_X, 32767);  // the wheel to its right stop: +450 deg (less half a count)
  wheel.press(BTN_0, true);  // the fluoroscopy pedal
  usleep(20000);
  ASSERT_TRUE(dev.read(0.010, r));
  EXPECT_NEAR(r.insertion_mm, 200.0, 1e-9);
  EXPECT_NEAR(r.rotation_rad, 450.0 * std::numbers::pi / 180.0, 450.0 / 65535 * std::numbers::pi / 180.0 + 1e-12);
  EXPECT_EQ(r.buttons, 1);
  EXPECT_GT(r.insertion_rate_mm_s, 0.0) << "moved since the first read";
  wheel.move(ABS_Y, 0);
  wheel.move(ABS_X, -32768);
  wheel.press(BTN_0, false);
  wheel.press(BTN_2, true);  // contrast
  usleep(20000);
  ASSERT_TRUE(dev.read(0.020, r));
  EXPECT_NEAR(r.insertion_mm, 0.0, 1e-9);
  EXPECT_NEAR(r.rotation_rad, -450.0 * std::numbers::pi / 180.0, 1e-2);
  EXPECT_EQ(r.buttons, 4);
  usleep(20000);
  ASSERT_TRUE(dev.read(0.100, r)) << "a still device is not a fault";
  EXPECT_EQ(r.insertion_rate_mm_s, 0.0) << "no event for 80 ms: still";
  wheel.unplug();
  EXPECT_FALSE(dev.read(0.110, r)) << "an unplugged device faults";
  EXPECT_FALSE(dev.render({0.0, 5.0}, 1));
}

TEST_F(UinputTest, TheTorqueIsOneConstantEffectUpdatedInPlaceStoppedAtZeroAndErasedOnExit) {
  UinputWheel wheel;
  EvdevConfig cfg;
  cfg.full_scale_torque_nmm = 20.0;
  cfg.gain = 0.5;
  {
    EvdevDevice dev(wheel.event_path(), cfg);
    EXPECT_TRUE(dev.has_gain());
    // each set-point applied by the device's writer thread before the next (flush)
    auto render = [&](double torque_nmm, int64_t seq) {
      ForceSetpoint f;
      f.torque_nmm = torque_nmm;
      EXPECT_TRUE(dev.render(f, seq));
      EXPECT_TRUE(dev.flush());
    };
    render(10.0, 1);
    render(10.0, 2);  // the same level: nothing sent
    render(-5.0, 3);
    EXPECT_EQ(dev.uploads(), 2);
    EXPECT_TRUE(dev.playing());
    // the 1 kHz loop's side allocates nothing (a level change each tick; the writer takes the newest)
    {
      pcisim::realtime::AllocationCount count;
      for (int k = 0; k < 100; ++k) ASSERT_TRUE(dev.render({0.0, 1.0 + 0.1 * k}, 4 + k));
      EXPECT_EQ(count.allocations(), 0);
    }
    ASSERT_TRUE(dev.flush());
    EXPECT_EQ(dev.level(), constant_level(1.0 + 0.1 * 99, 20.0)) << "the newest level was applied";
    render(0.0, 200);  // zero: the effect stops
    EXPECT_FALSE(dev.playing());
    render(4.0, 201);  // and plays again
    EXPECT_TRUE(dev.playing());
  }
  const auto erased = wait_for(wheel, FfRecord::kErase, 1);
  const auto all = wheel.records();
  const auto uploads = of(all, FfRecord::kUpload), plays = of(all, FfRecord::kPlay), stops = of(all, FfRecord::kStop);
  ASSERT_GE(uploads.size(), 3u);
  EXPECT_EQ(uploads[0].type, FF_CONSTANT);
  EXPECT_EQ(uploads[0].level, 16384);
  EXPECT_EQ(uploads[1].level, -8192);  // -5 / 20 * 32767 = -8191.75
  for (const FfRecord& u : uploads) EXPECT_EQ(u.id, uploads[0].id) << "one effect, updated in place";
  EXPECT_EQ(uploads.back().level, constant_level(4.0, 20.0));
  EXPECT_EQ(uploads[uploads.size() - 2].level, constant_level(1.0 + 0.1 * 99, 20.0));
  ASSERT_EQ(plays.size(), 2u) << "played at the first torque and again after the zero";
  // stopped at the zero, and on exit by the device and by the kernel as it erases the effect
  ASSERT_EQ(stops.size(), 3u) << "stops";
  EXPECT_LT(stops[0].t_ns, plays[1].t_ns) << "the zero's stop came before the second play";
  EXPECT_LE(stops[2].t_ns, erased[0].t_ns);
  ASSERT_EQ(erased.size(), 1u);
  EXPECT_EQ(erased[0].id, uploads[0].id);
  const auto gain = of(all, FfRecord::kGain), centre = of(all, FfRecord::kAutocenter);
  ASSERT_EQ(gain.size(), 1u);
  EXPECT_EQ(gain[0].value, 0x8000);  // 0.5 of 0xffff, rounded
  ASSERT_EQ(centre.size(), 1u);
  EXPECT_EQ(centre[0].value, 0) << "the device's own centring spring off";
}

// a zero (every fault sends one) handed over and at once replaced by a force is not skipped: the
// writer stops the effect before it plays the newer force
TEST_F(UinputTest, AZeroReplacedAtOnceStillStopsTheEffect) {
  UinputWheel wheel;
  EvdevDevice dev(wheel.event_path(), EvdevConfig{});
  ForceSetpoint f;
  f.torque_nmm = 5.0;
  ASSERT_TRUE(dev.render(f, 1));
  ASSERT_TRUE(dev.flush());
  ASSERT_TRUE(dev.playing());
  ASSERT_TRUE(dev.render({}, 2));  // a one-tick fault
  f.torque_nmm = 6.0;
  ASSERT_TRUE(dev.render(f, 3));  // at once (whether or not the writer got to the zero first)
  ASSERT_TRUE(dev.flush());
  EXPECT_TRUE(dev.playing());
  // plays and stops reach the wheel's maker as events, after the write returns (uploads are
  // answered, so they are recorded at once): wait up to 1 s for the third
  std::vector<FfRecord> plays_and_stops;
  for (int i = 0; i < 200 && plays_and_stops.size() < 3; ++i) {
    if (i > 0) usleep(5000);
    plays_and_stops.clear();
    for (const FfRecord& r : wheel.records())
      if (r.kind == FfRecord::kPlay || r.kind == FfRecord::kStop) plays_and_stops.push_back(r);
  }
  ASSERT_EQ(plays_and_stops.size(), 3u);
  EXPECT_EQ(plays_and_stops[0].kind, FfRecord::kPlay);
  EXPECT_EQ(plays_and_stops[1].kind, FfRecord::kStop) << "the zero reached the device";
  EXPECT_EQ(plays_and_stops[2].kind, FfRecord::kPlay);
}

TEST_F(UinputTest, AFlippedWheelFlipsTheTorqueSoThatItStillResists) {
  UinputWheel wheel;
  EvdevConfig cfg;
  cfg.wheel_range_deg = -900.0;  // the wheel's axis runs against the wire's rotation
  EvdevDevice dev(wheel.event_path(), cfg);
  ASSERT_TRUE(dev.render({0.0, 10.0}, 1));
  ASSERT_TRUE(dev.flush());
  EXPECT_EQ(dev.level(), -constant_level(10.0, cfg.full_scale_torque_nmm));
}

TEST_F(UinputTest, TheStiffnessIsASpringCentredWhereTheWheelStoodAtTheSampleTheTorqueAnswers) {
  UinputWheel wheel;
  EvdevConfig cfg;
  cfg.full_scale_torque_nmm = 20.0;
  cfg.wheel_range_deg = 900.0;
  // 1 N mm / rad over half the wheel's range (7.854 rad) is 7.854 N mm: 0.3927 of full scale
  const int16_t coeff = spring_coefficient(1.0, cfg);
  EXPECT_EQ(coeff, 12868);
  {
    EvdevDevice dev(wheel.event_path(), cfg);
    ASSERT_TRUE(dev.has_spring());
    InstrumentReading r;
    // a set-point with torque, stiffness and the tick whose sample it answers, applied at tick seq
    auto render = [&](double stiffness, int64_t answers, int64_t seq) {
      ForceSetpoint f;
      f.torque_nmm = 2.0;
      f.torsional_stiffness_nmm_per_rad = stiffness;
      f.sample_seq = answers;
      EXPECT_TRUE(dev.render(f, seq));
      EXPECT_TRUE(dev.flush());
    };
    ASSERT_TRUE(dev.read(0.0, r));
    render(1.0, -1, 1);  // answers no sample: centred where the wheel is (0)
    EXPECT_TRUE(dev.spring_playing());
    wheel.move(ABS_X, 16384);  // a quarter turn of the axis to the right
    usleep(20000);
    ASSERT_TRUE(dev.read(0.020, r));
    render(1.0, 1, 2);  // answers tick 1's sample: still centred at 0, so it pushes back the quarter turn
    EXPECT_EQ(dev.spring_uploads(), 1);
    render(1.0, 2, 3);  // answers tick 2's: re-centred where the wheel now is
    render(1.0, 3, 4);  // unmoved: nothing sent
    EXPECT_EQ(dev.spring_uploads(), 2);
    render(0.0, 4, 5);  // no stiffness: the spring stops
    EXPECT_FALSE(dev.spring_playing());
    EXPECT_TRUE(dev.playing()) << "the torque goes on";
    render(2.0, 5, 6);
    ASSERT_TRUE(dev.render({}, 7));  // zero, as in every fault: both stop
    ASSERT_TRUE(dev.flush());
    EXPECT_FALSE(dev.spring_playing());
    EXPECT_FALSE(dev.playing());
  }
  wait_for(wheel, FfRecord::kErase, 2);
  const auto all = wheel.records();
  std::vector<FfRecord> springs, constants;
  for (const FfRecord& u : of(all, FfRecord::kUpload)) (u.type == FF_SPRING ? springs : constants).push_back(u);
  ASSERT_EQ(springs.size(), 3u);
  ASSERT_FALSE(constants.empty());
  EXPECT_NE(springs[0].id, constants[0].id) << "two effects";
  EXPECT_EQ(springs[0].coeff, coeff);
  EXPECT_NEAR(springs[0].centre, 0, 1);
  EXPECT_EQ(springs[1].coeff, coeff);
  EXPECT_NEAR(springs[1].centre, 16384, 1);
  EXPECT_EQ(springs[2].coeff, spring_coefficient(2.0, cfg));
  for (const FfRecord& u : springs) EXPECT_EQ(u.id, springs[0].id) << "one spring, updated in place";
  const auto erased = of(all, FfRecord::kErase);
  ASSERT_EQ(erased.size(), 2u);
  EXPECT_NE(erased[0].id, erased[1].id);
}

// the bridge on the wheel: a server's torque and stiffness reach the device as the constant
// effect's level and the spring's coefficient, and when the server falls silent both are stopped
// within 50 ms (the bridge's gate sends zero)
TEST_F(UinputTest, TheBridgeRendersTheServersTorqueAndStopsItWhenTheServerFallsSilent) {
  UinputWheel wheel;
  lcm::LCM lcm("memq://");
  EvdevDevice dev(wheel.event_path(), EvdevConfig{});
  const int64_t t0_ns = realtime::monotonic_ns();
  constexpr double kSilentS = 0.30;
  std::atomic<bool> done{false};
  std::thread server([&] {
    pcisim_lcm::force_command_t m{};
    for (int64_t seq = 0; !done; ++seq) {
      if ((realtime::monotonic_ns() - t0_ns) * 1e-9 < kSilentS) {
        m.seq = seq;
        m.torque_nmm = 5.0;
        m.torsional_stiffness_nmm_per_rad = 0.5;
        lcm.publish(protocol::kForceChannel, &m);
      }
      usleep(1000);
    }
  });
  BridgeOptions o;
  o.duration_s = 0.5;
  o.log_each_second = false;
  Bridge bridge(lcm, dev, o);
  std::atomic<bool> stop{false};
  const BridgeStats stats = bridge.run(stop);
  done = true;
  server.join();
  // the 1 kHz loop's side of a write: the hand-over to the device's writer (a figure, not a bound)
  std::printf("the device write in the bridge's loop: p50 %.1f us, p99 %.1f us, max %.1f us over %lld ticks\n",
              stats.device_write.percentile_us(0.5), stats.device_write.percentile_us(0.99),
              stats.device_write.max_us(), static_cast<long long>(stats.device_write.count()));
  const auto all = wheel.records();
  std::vector<FfRecord> springs, constants;
  for (const FfRecord& u : of(all, FfRecord::kUpload)) (u.type == FF_SPRING ? springs : constants).push_back(u);
  ASSERT_FALSE(constants.empty());
  ASSERT_FALSE(springs.empty());
  EXPECT_EQ(constants.back().level, constant_level(5.0, EvdevConfig{}.full_scale_torque_nmm));
  EXPECT_EQ(springs.back().coeff, spring_coefficient(0.5, EvdevConfig{}));
  // both effects stopped, each within 50 ms of the server's silence
  const auto stops = of(all, FfRecord::kStop);
  ASSERT_EQ(stops.size(), 2u) << "the torque and the spring stopped once each";
  EXPECT_NE(stops[0].id, stops[1].id);
  for (const FfRecord& stop : stops) {
    const double stop_after_s = (stop.t_ns - t0_ns) * 1e-9 - kSilentS;
    std::printf("effect %d stopped %.1f ms after the server fell silent\n", stop.id, 1e3 * stop_after_s);
    EXPECT_GT(stop_after_s, 0.0);
    EXPECT_LT(stop_after_s, 0.050);
  }
}

}  // namespace
}  // namespace pcisim::clients
