#include "protocol/message_checks.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "pcisim_lcm/xray_frame_t.hpp"
#include "protocol/channels.h"

namespace pcisim::protocol {
namespace {

template <class M>
std::vector<uint8_t> encode(const M& m) {
  std::vector<uint8_t> bytes(m.getEncodedSize());
  EXPECT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  return bytes;
}

lcm::ReceiveBuffer as_rbuf(std::vector<uint8_t>& bytes) {
  lcm::ReceiveBuffer r;
  r.data = bytes.data();
  r.data_size = static_cast<uint32_t>(bytes.size());
  r.recv_utime = 0;
  return r;
}

pcisim_lcm::instrument_state_t instrument() {
  pcisim_lcm::instrument_state_t m{};
  m.utime = 123;
  m.seq = 7;
  m.insertion_mm = 42.5;
  m.rotation_rad = -1.25;
  m.buttons = pcisim_lcm::instrument_state_t::BUTTON_FLUORO_PEDAL;
  return m;
}

TEST(MessageChecks, GoodMessageDecodes) {
  auto bytes = encode(instrument());
  pcisim_lcm::instrument_state_t out{};
  ASSERT_TRUE(decode_checked(as_rbuf(bytes), out));
  EXPECT_EQ(out.seq, 7);
  EXPECT_DOUBLE_EQ(out.insertion_mm, 42.5);
  EXPECT_EQ(out.buttons, pcisim_lcm::instrument_state_t::BUTTON_FLUORO_PEDAL);
}

TEST(MessageChecks, WrongFingerprintTruncationTrailingBytesAndNanAreRejected) {
  pcisim_lcm::instrument_state_t out{};
  pcisim_lcm::force_command_t other{};
  auto wrong_type = encode(other);
  EXPECT_FALSE(decode_checked(as_rbuf(wrong_type), out)) << "wrong fingerprint";

  auto truncated = encode(instrument());
  truncated.resize(truncated.size() - 5);
  EXPECT_FALSE(decode_checked(as_rbuf(truncated), out)) << "truncated";

  auto trailing = encode(instrument());
  trailing.push_back(0);
  EXPECT_FALSE(decode_checked(as_rbuf(trailing), out)) << "trailing bytes";

  for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    auto m = instrument();
    m.rotation_rate_rad_s = bad;
    auto bytes = encode(m);
    EXPECT_FALSE(decode_checked(as_rbuf(bytes), out)) << bad;
  }
}

// the probe's pose (the soft-tissue scene's instrument): a good pose decodes; a NaN anywhere, a
// quaternion that is not a unit one, a position beyond 10 m, a depth or gain out of range do not
TEST(MessageChecks, ProbePoseIsAFiniteUnitQuaternionAndAPositionInReach) {
  pcisim_lcm::probe_state_t good{};
  good.utime = 5;
  good.position_mm[0] = 12.0;
  good.position_mm[2] = -80.0;
  good.orientation_wxyz[0] = std::cos(0.3);
  good.orientation_wxyz[3] = std::sin(0.3);
  good.depth_mm = 120.0;
  good.gain_db = -6.0;
  pcisim_lcm::probe_state_t out{};
  auto bytes = encode(good);
  ASSERT_TRUE(decode_checked(as_rbuf(bytes), out));
  EXPECT_DOUBLE_EQ(out.position_mm[2], -80.0);
  EXPECT_DOUBLE_EQ(out.orientation_wxyz[3], std::sin(0.3));
  struct Bad {
    const char* what;
    void (*spoil)(pcisim_lcm::probe_state_t&);
  };
  const Bad bad[] = {
      {"NaN position",
       [](pcisim_lcm::probe_state_t& m) { m.position_mm[1] = std::numeric_limits<double>::quiet_NaN(); }},
      {"Inf quaternion",
       [](pcisim_lcm::probe_state_t& m) { m.orientation_wxyz[2] = std::numeric_limits<double>::infinity(); }},
      {"zero quaternion", [](pcisim_lcm::probe_state_t& m) { m.orientation_wxyz[0] = m.orientation_wxyz[3] = 0.0; }},
      {"scaled quaternion", [](pcisim_lcm::probe_state_t& m) { m.orientation_wxyz[0] *= 1.05; }},
      {"11 m away", [](pcisim_lcm::probe_state_t& m) { m.position_mm[0] = 1.1e4; }},
      {"10.4 m away on a diagonal",
       [](pcisim_lcm::probe_state_t& m) { m.position_mm[0] = m.position_mm[1] = m.position_mm[2] = 6e3; }},
      {"negative depth", [](pcisim_lcm::probe_state_t& m) { m.depth_mm = -1.0; }},
      {"a depth of 1e-300 mm", [](pcisim_lcm::probe_state_t& m) { m.depth_mm = 1e-300; }},
      {"gain 80 dB", [](pcisim_lcm::probe_state_t& m) { m.gain_db = 80.0; }},
  };
  for (const Bad& b : bad) {
    pcisim_lcm::probe_state_t m = good;
    b.spoil(m);
    auto spoiled = encode(m);
    EXPECT_FALSE(decode_checked(as_rbuf(spoiled), out)) << b.what;
  }
}

TEST(MessageChecks, WireStateWithNonFiniteNodeIsRejected) {
  pcisim_lcm::wire_state_t m{};
  m.num_nodes = 2;
  m.node_mm = {{0, 0, 0}, {1, 2, 3}};
  m.contact = {0, 1};
  auto good = encode(m);
  pcisim_lcm::wire_state_t out{};
  ASSERT_TRUE(decode_checked(as_rbuf(good), out));
  EXPECT_FLOAT_EQ(out.node_mm[1][2], 3.0f);
  m.node_mm[1][1] = std::numeric_limits<float>::infinity();
  auto bad = encode(m);
  EXPECT_FALSE(decode_checked(as_rbuf(bad), out));
}

TEST(MessageChecks, InstrumentRatesBeyondAnyHandAreRefused) {
  auto m = instrument();
  EXPECT_TRUE(is_well_formed(m));
  m.insertion_rate_mm_s = 1e308;  // finite, but it would overflow the passivity observer
  EXPECT_FALSE(is_well_formed(m));
  m = instrument();
  m.rotation_rate_rad_s = -5e3;
  EXPECT_FALSE(is_well_formed(m));
}

TEST(MessageChecks, XrayFrameSizeAndPixelFormatAreChecked) {
  using F = pcisim_lcm::xray_frame_t;
  F m{};
  m.width = 4;
  m.height = 2;
  m.pixel_format = F::FORMAT_GRAY16;
  m.num_bytes = 16;
  m.data.assign(16, 0);
  m.pixel_mm = 0.4;
  EXPECT_TRUE(is_well_formed(m));
  m.num_bytes = 15;
  m.data.resize(15);
  EXPECT_FALSE(is_well_formed(m)) << "too few bytes for 4 x 2 x 16 bits";
  m.pixel_format = F::FORMAT_PNG;
  EXPECT_TRUE(is_well_formed(m)) << "compressed: any size";
  m.pixel_format = 7;
  EXPECT_FALSE(is_well_formed(m)) << "no such format: its size cannot be checked, so it is refused";
}

// every type survives an encode/decode over a real in-process LCM (memq)
TEST(MessageChecks, RoundTripOverMemq) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  struct Sink {
    int got = 0;
    pcisim_lcm::session_command_t session{};
    pcisim_lcm::sim_status_t status{};
    void on_session(const lcm::ReceiveBuffer* r, const std::string&) { got += decode_checked(*r, session); }
    void on_status(const lcm::ReceiveBuffer* r, const std::string&) { got += decode_checked(*r, status); }
  } sink;
  lcm.subscribe(kSessionChannel, &Sink::on_session, &sink);
  lcm.subscribe(kStatusChannel, &Sink::on_status, &sink);

  pcisim_lcm::session_command_t cmd{};
  cmd.command = pcisim_lcm::session_command_t::CMD_CARM;
  cmd.scene_path = "scenes/minimal.json";
  cmd.primary_angle_deg = 30;
  cmd.secondary_angle_deg = -20;
  lcm.publish(kSessionChannel, &cmd);
  pcisim_lcm::sim_status_t st{};
  st.haptic_rate_hz = 999.5;
  st.num_effects = 2;
  st.effect_name = {"guidewire", "friction"};
  st.effect_step_ms_p50 = {0.4, 0.1};
  lcm.publish(kStatusChannel, &st);
  while (sink.got < 2) ASSERT_EQ(lcm.handleTimeout(1000), 1) << "message did not arrive";
  EXPECT_EQ(sink.session.scene_path, "scenes/minimal.json");
  EXPECT_DOUBLE_EQ(sink.session.secondary_angle_deg, -20);
  EXPECT_EQ(sink.status.effect_name[1], "friction");
  EXPECT_DOUBLE_EQ(sink.status.haptic_rate_hz, 999.5);
}

}  // namespace
}  // namespace pcisim::protocol
