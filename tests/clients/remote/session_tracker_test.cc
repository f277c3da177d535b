// The cath-lab metrics the gateway keeps because the server does not report them: fluoroscopy
// time (pedal-down time, console or instrument) and contrast used (injections x volume).
#include <gtest/gtest.h>

#include "clients/remote/session_tracker.h"

namespace pcisim::remote {
namespace {

using C = pcisim_lcm::session_command_t;
using I = pcisim_lcm::instrument_state_t;
constexpr int64_t kS = 1'000'000'000;

C pedal(int8_t cmd, bool down) {
  C c{};
  c.command = cmd;
  c.pedal_down = down;
  return c;
}

I instrument(int32_t buttons, int32_t device = 1) {
  I m{};
  m.device_id = device;
  m.buttons = buttons;
  return m;
}

TEST(RemoteTracker, FluoroTimeIsPedalDownTimeFromConsoleOrInstrument) {
  SessionTracker t;
  t.on_session(pedal(C::CMD_FLUORO_PEDAL, true), 10 * kS);
  EXPECT_NEAR(t.fluoro_time_s(12 * kS), 2.0, 1e-9);
  t.on_session(pedal(C::CMD_FLUORO_PEDAL, false), 13 * kS);
  EXPECT_NEAR(t.fluoro_time_s(20 * kS), 3.0, 1e-9);
  // the instrument's pedal and a console cine overlapping count once
  t.on_instrument(instrument(I::BUTTON_FLUORO_PEDAL), 20 * kS);
  t.on_session(pedal(C::CMD_CINE, true), 21 * kS);
  t.on_instrument(instrument(0), 22 * kS);
  t.on_session(pedal(C::CMD_CINE, false), 23 * kS);
  EXPECT_NEAR(t.fluoro_time_s(30 * kS), 6.0, 1e-9);
  const auto j = t.state_json(30 * kS);
  EXPECT_FALSE(j["fluoro"]["on"].get<bool>());
  EXPECT_NEAR(j["fluoro"]["time_s"].get<double>(), 6.0, 1e-9);
}

TEST(RemoteTracker, ContrastCountsCommandsAndButtonPresses) {
  TrackerOptions o;
  o.injection_ml = 8;
  SessionTracker t(o);
  C c{};
  c.command = C::CMD_CONTRAST;
  t.on_session(c, kS);
  t.on_instrument(instrument(I::BUTTON_CONTRAST), 2 * kS);
  t.on_instrument(instrument(I::BUTTON_CONTRAST), 2 * kS + 1000);  // still held: one injection
  t.on_instrument(instrument(0), 3 * kS);
  t.on_instrument(instrument(I::BUTTON_CONTRAST), 4 * kS);
  EXPECT_EQ(t.injections(), 3);
  EXPECT_DOUBLE_EQ(t.state_json(5 * kS)["contrast"]["used_ml"].get<double>(), 24.0);
  // a command that names its volume counts that, as the server does; an absurd one the scene's
  c.contrast_ml = 5;
  t.on_session(c, 6 * kS);
  c.contrast_ml = 500;
  t.on_session(c, 7 * kS);
  EXPECT_DOUBLE_EQ(t.state_json(8 * kS)["contrast"]["used_ml"].get<double>(), 37.0);
}

TEST(RemoteTracker, ServerFiguresWinAndTheBusAddsWhatCameSince) {
  // a gateway that joins late: the server has counted 100 s of beam and 3 injections (30 ml)
  TrackerOptions o;
  o.injection_ml = 8;
  SessionTracker t(o);
  pcisim_lcm::sim_status_t s{};
  s.fluoro_time_s = 100.0;
  s.contrast_injections = 3;
  s.contrast_ml = 30.0;
  t.on_status(s, kS);
  EXPECT_NEAR(t.fluoro_time_s(2 * kS), 100.0, 1e-9);
  // until the next report, pedal time and injections seen on the bus add to it
  t.on_session(pedal(C::CMD_FLUORO_PEDAL, true), 2 * kS);
  C c{};
  c.command = C::CMD_CONTRAST;
  t.on_session(c, 3 * kS);
  const auto j = t.state_json(4 * kS);
  EXPECT_NEAR(j["fluoro"]["time_s"].get<double>(), 102.0, 1e-9);
  EXPECT_EQ(j["contrast"]["injections"].get<int>(), 4);
  EXPECT_DOUBLE_EQ(j["contrast"]["used_ml"].get<double>(), 38.0);
  // the next report includes them: nothing is counted twice
  s.fluoro_time_s = 103.0;
  s.contrast_injections = 4;
  s.contrast_ml = 40.0;
  t.on_status(s, 5 * kS);
  EXPECT_NEAR(t.fluoro_time_s(6 * kS), 104.0, 1e-9);  // the pedal is still down
  EXPECT_EQ(t.injections(), 4);
  EXPECT_DOUBLE_EQ(t.state_json(6 * kS)["contrast"]["used_ml"].get<double>(), 40.0);
}

// issue #35: the server's debrief so far rides the status to the page; a figure the session cannot
// give (no target, a wire without wall forces) goes as null, never as a made-up zero
TEST(RemoteTracker, TheDebriefSoFarRidesTheStatus) {
  SessionTracker t;
  pcisim_lcm::sim_status_t s{};
  t.on_status(s, kS);
  EXPECT_TRUE(t.status_json(kS)["debrief"].is_null()) << "none before the first";
  pcisim_lcm::session_metrics_t m{};
  m.seq = 4;
  m.fluoro_time_s = 12.5;
  m.cine_runs = 2;
  m.air_kerma_mgy = 3.9;
  m.tip_path_in_vessels_mm = 124;
  m.has_target = 1;
  m.target_branch = "LAD";
  m.wrong_branch_s = 0.5;
  m.target_reached_s = -1;
  t.on_metrics(m, 2 * kS);
  const auto d = t.status_json(2 * kS)["debrief"];
  EXPECT_EQ(d["seq"].get<int>(), 4);
  EXPECT_DOUBLE_EQ(d["fluoro_time_s"].get<double>(), 12.5);
  EXPECT_EQ(d["cine_runs"].get<int>(), 2);
  EXPECT_DOUBLE_EQ(d["air_kerma_mgy"].get<double>(), 3.9);
  EXPECT_DOUBLE_EQ(d["wrong_branch_s"].get<double>(), 0.5);
  EXPECT_EQ(d["target_branch"], "LAD");
  EXPECT_TRUE(d["target_reached_s"].is_null()) << "not reached yet";
  EXPECT_TRUE(d["peak_tip_force_n"].is_null()) << "the chain-mail computes no wall force";
  m.has_target = 0;
  m.tip_forces_known = 1;
  m.peak_tip_force_n = 0.2;
  t.on_metrics(m, 3 * kS);
  const auto e = t.status_json(3 * kS)["debrief"];
  EXPECT_TRUE(e["wrong_branch_s"].is_null());
  EXPECT_DOUBLE_EQ(e["peak_tip_force_n"].get<double>(), 0.2);
}

TEST(RemoteTracker, CarmFollowsAcceptedCommandsAndFrames) {
  SessionTracker t;
  EXPECT_TRUE(t.state_json(kS)["carm"]["primary_deg"].is_null()) << "unknown until told";
  C c{};
  c.command = C::CMD_CARM;
  c.primary_angle_deg = 30;
  c.secondary_angle_deg = -20;
  t.on_session(c, kS);
  c.primary_angle_deg = 500;  // the server ignores this one, so do we
  t.on_session(c, kS);
  EXPECT_DOUBLE_EQ(t.state_json(kS)["carm"]["primary_deg"].get<double>(), 30);
  pcisim_lcm::xray_frame_t f{};
  f.primary_angle_deg = -10;
  f.secondary_angle_deg = 5;
  t.on_frame(f, 2 * kS);
  EXPECT_DOUBLE_EQ(t.state_json(2 * kS)["carm"]["secondary_deg"].get<double>(), 5);
}

TEST(RemoteTracker, OtherInstrumentIsActiveWhileHeard) {
  TrackerOptions o;
  o.own_device_id = 90;
  SessionTracker t(o);
  t.on_instrument(instrument(0, 90), kS);
  EXPECT_FALSE(t.other_instrument_active(kS)) << "our own keyboard samples do not count";
  t.on_instrument(instrument(0, 3), kS);
  EXPECT_TRUE(t.other_instrument_active(kS + 100'000'000));
  EXPECT_FALSE(t.other_instrument_active(kS + 300'000'000));
}

}  // namespace
}  // namespace pcisim::remote
