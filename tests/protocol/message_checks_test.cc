#include "protocol/message_checks.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <vector>

#include "pcisim_lcm/us_frame_t.hpp"
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
  m.contact_force_n = {{0, 0, 0}, {0, -0.5f, 0}};
  auto good = encode(m);
  pcisim_lcm::wire_state_t out{};
  ASSERT_TRUE(decode_checked(as_rbuf(good), out));
  EXPECT_FLOAT_EQ(out.node_mm[1][2], 3.0f);
  EXPECT_FLOAT_EQ(out.contact_force_n[1][1], -0.5f);
  m.node_mm[1][1] = std::numeric_limits<float>::infinity();
  auto bad = encode(m);
  EXPECT_FALSE(decode_checked(as_rbuf(bad), out));
  // a non-finite force, on a node or at the hub, is refused as well
  m.node_mm[1][1] = 2;
  m.contact_force_n[0][2] = std::numeric_limits<float>::quiet_NaN();
  bad = encode(m);
  EXPECT_FALSE(decode_checked(as_rbuf(bad), out));
  m.contact_force_n[0][2] = 0;
  m.hub_force_n = std::numeric_limits<double>::infinity();
  bad = encode(m);
  EXPECT_FALSE(decode_checked(as_rbuf(bad), out));
}

TEST(MessageChecks, AForceCommandsStiffnessIsFiniteAndNotNegative) {
  pcisim_lcm::force_command_t m{};
  m.axial_force_n = 0.5;
  m.axial_stiffness_n_per_mm = 0.2;
  m.torsional_stiffness_nmm_per_rad = 3.0;
  EXPECT_TRUE(is_well_formed(m));
  m.torsional_stiffness_nmm_per_rad = -1.0;  // a negative spring pushes the hand on
  EXPECT_FALSE(is_well_formed(m));
  m.torsional_stiffness_nmm_per_rad = 0.0;
  m.axial_stiffness_n_per_mm = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(is_well_formed(m));
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

// an ultrasound frame as the soft-tissue scene sends it: linear, 40 mm wide, 60 mm deep
pcisim_lcm::us_frame_t us_frame() {
  using F = pcisim_lcm::us_frame_t;
  F m{};
  m.utime = 9;
  m.seq = 3;
  m.width = 4;
  m.height = 3;
  m.pixel_format = F::FORMAT_GRAY8;
  m.geometry = F::GEOMETRY_LINEAR;
  m.depth_mm = 60.0;
  m.width_mm = 40.0;
  m.gain_db = -6.0;
  m.frequency_mhz = 5.0;
  m.origin_mm[1] = -29.5;
  m.beam[1] = 1.0;
  m.lateral[0] = std::cos(0.2);  // in the x-z plane: perpendicular to the beam
  m.lateral[2] = std::sin(0.2);
  m.probe_force_n[1] = -2.5;
  m.sim_time_s = 1.25;
  m.num_bytes = 12;
  for (int i = 0; i < 12; ++i) m.data.push_back(static_cast<uint8_t>(20 * i));
  return m;
}

// a good frame decodes, linear and curvilinear; each spoiled field is refused: the sizes, the
// format and geometry, NaN anywhere, directions that are not an orthonormal pair, and the
// renderer's ranges (depth, gain, frequency and each geometry's own sizes)
TEST(MessageChecks, UltrasoundFrameGeometryFormatAndSizesAreChecked) {
  using F = pcisim_lcm::us_frame_t;
  F out{};
  auto bytes = encode(us_frame());
  ASSERT_TRUE(decode_checked(as_rbuf(bytes), out));
  EXPECT_EQ(out.data, us_frame().data);
  EXPECT_DOUBLE_EQ(out.lateral[2], std::sin(0.2));
  EXPECT_DOUBLE_EQ(out.probe_force_n[1], -2.5);

  F curved = us_frame();
  curved.geometry = F::GEOMETRY_CURVILINEAR;
  curved.width_mm = 0.0;  // a linear array's length: not read for a fan
  curved.fan_angle_deg = 60.0;
  curved.radius_of_curvature_mm = 40.0;
  auto curved_bytes = encode(curved);
  EXPECT_TRUE(decode_checked(as_rbuf(curved_bytes), out)) << "curvilinear";

  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  struct Bad {
    const char* what;
    std::function<void(F&)> spoil;
  };
  const auto resize = [](F& m, int w, int h) {
    m.width = w;
    m.height = h;
    m.num_bytes = std::max(0, w * h);
    m.data.assign(static_cast<size_t>(m.num_bytes), 7);
  };
  const auto fan = [](F& m) {
    m.geometry = F::GEOMETRY_CURVILINEAR;
    m.fan_angle_deg = 60.0;
    m.radius_of_curvature_mm = 40.0;
  };
  const Bad bad[] = {
      {"NaN origin", [&](F& m) { m.origin_mm[0] = nan; }},
      {"Inf probe force", [&](F& m) { m.probe_force_n[2] = inf; }},
      {"NaN sim time", [&](F& m) { m.sim_time_s = nan; }},
      {"NaN gain", [&](F& m) { m.gain_db = nan; }},
      {"NaN beam", [&](F& m) { m.beam[1] = nan; }},
      {"beam of length 1.1", [](F& m) { m.beam[1] = 1.1; }},
      {"zero beam", [](F& m) { m.beam[1] = 0.0; }},
      {"lateral of length 0.9", [](F& m) { m.lateral[0] *= 0.9, m.lateral[2] *= 0.9; }},
      {"lateral along the beam", [](F& m) { m.lateral[0] = m.lateral[2] = 0.0, m.lateral[1] = 1.0; }},
      {"lateral 1 degree off perpendicular",
       [](F& m) {
         const double a = std::numbers::pi / 180.0;
         m.lateral[0] = std::cos(a), m.lateral[1] = std::sin(a), m.lateral[2] = 0.0;
       }},
      {"one byte short of width x height", [](F& m) { m.num_bytes = 11, m.data.resize(11); }},
      {"one byte over width x height", [](F& m) { m.num_bytes = 13, m.data.push_back(0); }},
      {"negative width", [](F& m) { m.width = -4; }},
      {"negative width and height", [&](F& m) { m.width = m.height = -3, m.num_bytes = 9, m.data.resize(9); }},
      {"empty frame", [&](F& m) { resize(m, 0, 0); }},
      {"4097 columns", [&](F& m) { resize(m, 4097, 1); }},
      {"unknown format", [](F& m) { m.pixel_format = 2; }},
      {"format 0", [](F& m) { m.pixel_format = 0; }},
      {"unknown geometry", [](F& m) { m.geometry = 2; }},
      {"negative geometry", [](F& m) { m.geometry = -1; }},
      {"depth 0 mm", [](F& m) { m.depth_mm = 0.0; }},
      {"depth 301 mm", [](F& m) { m.depth_mm = 301.0; }},
      {"negative depth", [](F& m) { m.depth_mm = -60.0; }},
      {"gain 61 dB", [](F& m) { m.gain_db = 61.0; }},
      {"gain -61 dB", [](F& m) { m.gain_db = -61.0; }},
      {"frequency 0 MHz", [](F& m) { m.frequency_mhz = 0.0; }},
      {"frequency 21 MHz", [](F& m) { m.frequency_mhz = 21.0; }},
      {"linear of width 0 mm", [](F& m) { m.width_mm = 0.0; }},
      {"linear of width 201 mm", [](F& m) { m.width_mm = 201.0; }},
      {"negative width_mm", [](F& m) { m.width_mm = -40.0; }},
      {"curvilinear of fan 0 deg", [&](F& m) { fan(m), m.fan_angle_deg = 0.0; }},
      {"curvilinear of fan 151 deg", [&](F& m) { fan(m), m.fan_angle_deg = 151.0; }},
      {"curvilinear of radius 0 mm", [&](F& m) { fan(m), m.radius_of_curvature_mm = 0.0; }},
      {"curvilinear of radius 201 mm", [&](F& m) { fan(m), m.radius_of_curvature_mm = 201.0; }},
      {"curvilinear with a negative width_mm", [&](F& m) { fan(m), m.width_mm = -1.0; }},
      {"linear with a negative fan angle", [](F& m) { m.fan_angle_deg = -60.0; }},
  };
  for (const Bad& b : bad) {
    F m = us_frame();
    b.spoil(m);
    auto spoiled = encode(m);
    EXPECT_FALSE(decode_checked(as_rbuf(spoiled), out)) << b.what;
  }
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
