#include "clients/bridge/probe_script.h"

#include <gtest/gtest.h>

#include <tuple>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <vector>

#include "pcisim_lcm/probe_state_t.hpp"
#include "protocol/message_checks.h"

namespace pcisim::clients {
namespace {

using P = pcisim_lcm::probe_state_t;
constexpr double kDeg = std::numbers::pi / 180.0;

std::string error_of(const std::string& text) {
  try {
    ProbeScript::parse(text, "s.json");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

// a script of one keyframe with `extra` keys appended (a leading comma included)
std::string one_keyframe(const std::string& extra) {
  return R"({"keyframes": [{"t_s": 0, "position_mm": [0, 0, 0], "orientation_wxyz": [1, 0, 0, 0])" + extra + "}]}";
}

Eigen::Quaterniond quaternion(const std::array<double, 4>& wxyz) {
  return {wxyz[0], wxyz[1], wxyz[2], wxyz[3]};
}

// 10 mm along x, -4 along y, 2 along z and 90 deg about z from t = 1 s to 3 s; depth and gain set
// at the first keyframe, freeze pressed at the second
const char* kTwoKeyframes = R"({"name": "two", "keyframes": [
    {"t_s": 1, "position_mm": [0, 0, 0], "orientation_wxyz": [1, 0, 0, 0], "depth_mm": 60, "gain_db": -6},
    {"t_s": 3, "position_mm": [10, -4, 2], "orientation_wxyz": [0.7071067811865476, 0, 0, 0.7071067811865476],
     "freeze": true}]})";

TEST(ProbeScript, KeyframesAreExactAndHeldBeforeTheFirstAndAfterTheLast) {
  const auto s = ProbeScript::parse(kTwoKeyframes, "s");
  EXPECT_EQ(s.name(), "two");
  EXPECT_DOUBLE_EQ(s.duration_s(), 3.0);
  for (double t : {-1.0, 0.0, 1.0}) {
    const auto r = s.sample(t);
    EXPECT_EQ(r.position_mm, (std::array<double, 3>{0, 0, 0})) << t;
    EXPECT_EQ(r.orientation_wxyz, (std::array<double, 4>{1, 0, 0, 0})) << t;
    EXPECT_EQ(r.buttons, 0) << t;
  }
  for (double t : {3.0, 4.0, 1e6, std::nan("")}) {
    const auto r = s.sample(t);
    EXPECT_EQ(r.position_mm, (std::array<double, 3>{10, -4, 2})) << t;
    EXPECT_NEAR(r.orientation_wxyz[0], std::sqrt(0.5), 1e-15) << t;
    EXPECT_NEAR(r.orientation_wxyz[3], std::sqrt(0.5), 1e-15) << t;
    EXPECT_EQ(r.orientation_wxyz[1], 0.0);
    EXPECT_EQ(r.orientation_wxyz[2], 0.0);
    EXPECT_EQ(r.buttons, P::BUTTON_FREEZE) << t;
  }
}

TEST(ProbeScript, PositionIsLinearAndOrientationSlerpsBetweenKeyframes) {
  const auto s = ProbeScript::parse(kTwoKeyframes, "s");
  const Eigen::Quaterniond first = Eigen::Quaterniond::Identity();
  const Eigen::Quaterniond last(Eigen::AngleAxisd(90 * kDeg, Eigen::Vector3d::UnitZ()));
  for (const double u : {0.25, 0.5, 0.75}) {
    const auto r = s.sample(1.0 + 2.0 * u);
    EXPECT_DOUBLE_EQ(r.position_mm[0], 10 * u) << u;
    EXPECT_DOUBLE_EQ(r.position_mm[1], -4 * u) << u;
    EXPECT_DOUBLE_EQ(r.position_mm[2], 2 * u) << u;
    const Eigen::Quaterniond q = quaternion(r.orientation_wxyz);
    EXPECT_NEAR(q.norm(), 1.0, 1e-15);
    // the angle is u of the way (45 deg at the midpoint), about the same axis
    EXPECT_NEAR(first.angularDistance(q), u * 90 * kDeg, 1e-12) << u;
    EXPECT_NEAR(q.angularDistance(last), (1 - u) * 90 * kDeg, 1e-12) << u;
    const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
    EXPECT_NEAR((x - Eigen::Vector3d(std::cos(u * 90 * kDeg), std::sin(u * 90 * kDeg), 0)).norm(), 0, 1e-12) << u;
  }
}

TEST(ProbeScript, DepthGainAndFreezeStepAtTheirKeyframeAndCarryOver) {
  const auto s = ProbeScript::parse(kTwoKeyframes, "s");
  const auto before = s.sample(2.999);
  EXPECT_EQ(before.depth_mm, 60.0);
  EXPECT_EQ(before.gain_db, -6.0);
  EXPECT_EQ(before.buttons, 0) << "freeze comes with its keyframe, not before";
  const auto after = s.sample(3.0);
  EXPECT_EQ(after.depth_mm, 60.0) << "carried over from the keyframe before";
  EXPECT_EQ(after.gain_db, -6.0);
  EXPECT_EQ(after.buttons, P::BUTTON_FREEZE);
  // unset from the start: the scene's depth, no gain
  const auto plain = ProbeScript::parse(one_keyframe(""), "s").sample(0);
  EXPECT_EQ(plain.depth_mm, 0.0);
  EXPECT_EQ(plain.gain_db, 0.0);
  EXPECT_EQ(plain.buttons, 0);
}

TEST(ProbeScript, QuaternionsAreNormalisedOnReadAndSlerpTakesTheShorterArc) {
  const auto s = ProbeScript::parse(R"({"keyframes": [
      {"t_s": 0, "position_mm": [0, 0, 0], "orientation_wxyz": [2, 0, 0, 0]},
      {"t_s": 1, "position_mm": [0, 0, 0], "orientation_wxyz": [-3, 0, 0, -3]}]})",
                                    "s");
  EXPECT_EQ(s.sample(0).orientation_wxyz, (std::array<double, 4>{1, 0, 0, 0}));
  const Eigen::Quaterniond last = quaternion(s.sample(1).orientation_wxyz);
  EXPECT_NEAR(last.norm(), 1.0, 1e-15);
  // [-1, 0, 0, -1]/sqrt(2) is +90 deg about z, written as its negative: the midpoint is 45 deg, not 135
  const Eigen::Quaterniond mid = quaternion(s.sample(0.5).orientation_wxyz);
  EXPECT_NEAR(Eigen::Quaterniond::Identity().angularDistance(mid), 45 * kDeg, 1e-12);
}

TEST(ProbeScript, BadScriptsNameThePathAndTheRange) {
  EXPECT_EQ(error_of(one_keyframe(R"(, "colour": 1)")),
            "s.json: keyframes[0].colour: unknown key (this object accepts: depth_mm, freeze, gain_db, "
            "orientation_wxyz, position_mm, t_s)");
  EXPECT_EQ(error_of(R"({"name": "x", "frames": []})"),
            "s.json: frames: unknown key (this object accepts: keyframes, name)");
  EXPECT_EQ(error_of(R"({"keyframes": [
      {"t_s": 1, "position_mm": [0, 0, 0], "orientation_wxyz": [1, 0, 0, 0]},
      {"t_s": 1, "position_mm": [0, 0, 0], "orientation_wxyz": [1, 0, 0, 0]}]})"),
            "s.json: keyframes[1].t_s: expected a time after the previous keyframe's 1 s, got 1");
  EXPECT_EQ(error_of(R"({"keyframes": [
      {"t_s": 2, "position_mm": [0, 0, 0], "orientation_wxyz": [1, 0, 0, 0]},
      {"t_s": 1.5, "position_mm": [0, 0, 0], "orientation_wxyz": [1, 0, 0, 0]}]})"),
            "s.json: keyframes[1].t_s: expected a time after the previous keyframe's 2 s, got 1.5");
  EXPECT_EQ(error_of(R"({"keyframes": [{"t_s": 0, "position_mm": [0, 0, 0], "orientation_wxyz": [0, 0, 0, 0]}]})"),
            "s.json: keyframes[0].orientation_wxyz: expected [w, x, y, z], a finite quaternion of norm at least 1e-06 "
            "(normalised on read), got [0,0,0,0]");
  EXPECT_EQ(error_of(R"({"keyframes": [{"t_s": 0, "position_mm": [0, 0, 0], "orientation_wxyz": [1, 0, 0]}]})"),
            "s.json: keyframes[0].orientation_wxyz: expected [w, x, y, z], a finite quaternion of norm at least 1e-06 "
            "(normalised on read), got [1,0,0]");
  EXPECT_EQ(
      error_of(R"({"keyframes": [{"t_s": 0, "position_mm": [0, 0, 0], "orientation_wxyz": [1e300, 1e300, 0, 0]}]})"),
      "s.json: keyframes[0].orientation_wxyz: expected [w, x, y, z], a finite quaternion of norm at least 1e-06 "
      "(normalised on read), got [1e+300,1e+300,0,0]");
  EXPECT_EQ(error_of(one_keyframe(R"(, "depth_mm": 600)")),
            "s.json: keyframes[0].depth_mm: expected a number in [0, 500], got 600");
  EXPECT_EQ(error_of(one_keyframe(R"(, "depth_mm": 0.5)")),
            "s.json: keyframes[0].depth_mm: expected 0 (the scene's depth) or a depth in [1, 500] mm, got 0.5");
  EXPECT_EQ(error_of(one_keyframe(R"(, "gain_db": 61)")),
            "s.json: keyframes[0].gain_db: expected a number in [-60, 60], got 61");
  EXPECT_EQ(error_of(one_keyframe(R"(, "gain_db": -60.5)")),
            "s.json: keyframes[0].gain_db: expected a number in [-60, 60], got -60.5");
  EXPECT_EQ(error_of(one_keyframe(R"(, "freeze": 1)")), "s.json: keyframes[0].freeze: expected true or false, got 1");
  EXPECT_EQ(
      error_of(R"({"keyframes": [{"t_s": 0, "position_mm": [8000, 8000, 0], "orientation_wxyz": [1, 0, 0, 0]}]})"),
      "s.json: keyframes[0].position_mm: expected [x, y, z] in mm within 10000 mm of the scene's origin, got "
      "[8000,8000,0]");
  EXPECT_EQ(error_of(R"({"keyframes": [{"t_s": 0, "position_mm": [0, "a", 0], "orientation_wxyz": [1, 0, 0, 0]}]})"),
            "s.json: keyframes[0].position_mm: expected [x, y, z] in mm within 10000 mm of the scene's origin, got "
            "[0,\"a\",0]");
  EXPECT_EQ(error_of(R"({"keyframes": [{"t_s": 0, "orientation_wxyz": [1, 0, 0, 0]}]})"),
            "s.json: keyframes[0].position_mm: expected [x, y, z] in mm within 10000 mm of the scene's origin "
            "(required)");
  EXPECT_EQ(error_of(R"({"keyframes": [{"position_mm": [0, 0, 0], "orientation_wxyz": [1, 0, 0, 0]}]})"),
            "s.json: keyframes[0].t_s: expected a time in [0, 1000000] s (required)");
  EXPECT_EQ(error_of(R"({"keyframes": []})"), "s.json: keyframes: expected at least one keyframe");
  EXPECT_EQ(error_of(R"({"keyframes": {}})"), "s.json: keyframes: expected a list, got {}");
  EXPECT_EQ(error_of(R"({"keyframes": [3]})"), "s.json: keyframes[0]: expected an object");
  EXPECT_NE(error_of("{").find("s.json: not valid JSON"), std::string::npos);
}

TEST(ProbeScript, TheDecodersEdgesAreAccepted) {
  // the same ranges as protocol::decode_checked: depth 0, 1 and 500 mm, gain +-60 dB, 10 m away
  const auto s = ProbeScript::parse(R"({"keyframes": [
      {"t_s": 0, "position_mm": [10000, 0, 0], "orientation_wxyz": [1, 0, 0, 0], "depth_mm": 0, "gain_db": 60},
      {"t_s": 1, "position_mm": [0, -10000, 0], "orientation_wxyz": [1, 0, 0, 0], "depth_mm": 1, "gain_db": -60},
      {"t_s": 2, "position_mm": [0, 0, 0], "orientation_wxyz": [1, 0, 0, 0], "depth_mm": 500}]})",
                                    "s");
  EXPECT_EQ(s.sample(0).depth_mm, 0.0);
  EXPECT_EQ(s.sample(1).depth_mm, 1.0);
  EXPECT_EQ(s.sample(2).depth_mm, 500.0);
  EXPECT_EQ(s.sample(2).gain_db, -60.0);
}

// every 10 ms of a script, as the bridge would publish it, passes the decoder's checks
void expect_decodable(const ProbeScript& s) {
  for (double t = 0; t <= s.duration_s() + 0.5; t += 0.01) {
    const auto r = s.sample(t);
    P m{};
    m.status = P::STATUS_OK;
    m.buttons = r.buttons;
    for (int k = 0; k < 3; ++k) m.position_mm[k] = r.position_mm[k];
    for (int k = 0; k < 4; ++k) m.orientation_wxyz[k] = r.orientation_wxyz[k];
    m.depth_mm = r.depth_mm;
    m.gain_db = r.gain_db;
    std::vector<uint8_t> bytes(m.getEncodedSize());
    ASSERT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
    P back{};
    ASSERT_TRUE(protocol::decode_checked(bytes.data(), static_cast<int64_t>(bytes.size()), back)) << "t = " << t;
  }
}

TEST(ProbeScript, EverySampleIsAMessageTheDecoderAccepts) {
  expect_decodable(ProbeScript::parse(kTwoKeyframes, "s"));
  expect_decodable(ProbeScript::parse(ProbeScript::builtin_text(), "built-in"));
}

// the built-in probe on the kidney phantom (organ frame LPS, mm; anterior skin at y = -17.5): beam
// (probe z) posterior into the organ, image width (probe x) along the long axis S
TEST(ProbeScript, BuiltInPressesTheKidneyFromAnteriorWithTheImageAlongItsLongAxis) {
  const auto s = ProbeScript::parse(ProbeScript::builtin_text(), "built-in");
  EXPECT_EQ(s.name(), "kidney-press");
  EXPECT_DOUBLE_EQ(s.duration_s(), 10.0);
  const Eigen::Quaterniond base = quaternion(s.sample(0).orientation_wxyz);
  const Eigen::Matrix3d R = base.toRotationMatrix();
  EXPECT_NEAR((R * Eigen::Vector3d(0, 0, 1) - Eigen::Vector3d(0, 1, 0)).norm(), 0, 1e-15) << "beam to +y";
  EXPECT_NEAR((R * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(0, 0, 1)).norm(), 0, 1e-15) << "lateral to +z";
  EXPECT_NEAR((R * Eigen::Vector3d(0, 1, 0) - Eigen::Vector3d(1, 0, 0)).norm(), 0, 1e-15) << "elevation to +x";
  EXPECT_NEAR(R.determinant(), 1.0, 1e-15);
  // -90 deg about x alone gets the beam right but leaves the image across the organ (along x)
  const Eigen::Quaterniond about_x(std::cos(-45 * kDeg), std::sin(-45 * kDeg), 0, 0);
  EXPECT_NEAR((about_x * Eigen::Vector3d(0, 0, 1) - Eigen::Vector3d(0, 1, 0)).norm(), 0, 1e-15);
  EXPECT_NEAR((about_x * Eigen::Vector3d(1, 0, 0) - Eigen::Vector3d(1, 0, 0)).norm(), 0, 1e-15);
  const Eigen::Quaterniond about_z(std::cos(-45 * kDeg), 0, 0, std::sin(-45 * kDeg));
  EXPECT_NEAR(base.angularDistance(about_x * about_z), 0, 1e-12);

  struct Expect {
    double t_s, x_mm, y_mm, z_mm, tilt_deg;
  };
  // 5 mm above the skin, pressed 8 mm in, slid 15 mm toward S, tilted 15 deg and back, withdrawn
  // the image deepened and brightened once pressed, the scene's depth and gain back on withdrawal
  for (auto [t_s, depth_mm, gain_db] :
       {std::tuple{3.0, 0.0, 0.0}, std::tuple{3.5, 80.0, 6.0}, std::tuple{8.0, 80.0, 6.0}, std::tuple{9.5, 0.0, 0.0}}) {
    EXPECT_EQ(s.sample(t_s).depth_mm, depth_mm) << t_s;
    EXPECT_EQ(s.sample(t_s).gain_db, gain_db) << t_s;
  }
  for (const Expect& e :
       {Expect{0.0, 0, -22.5, 0, 0}, Expect{0.5, 0, -22.5, 0, 0}, Expect{1.5, 0, -16, 0, 0}, Expect{2.5, 0, -9.5, 0, 0},
        Expect{3.5, 0, -9.5, 0, 0}, Expect{4.5, 0, -9.5, 7.5, 0}, Expect{5.5, 0, -9.5, 15, 0},
        Expect{6.0, 0, -9.5, 15, 7.5}, Expect{6.5, 0, -9.5, 15, 15}, Expect{7.5, 0, -9.5, 15, 0},
        Expect{9.0, 0, -22.5, 15, 0}, Expect{10.0, 0, -22.5, 15, 0}, Expect{12.0, 0, -22.5, 15, 0}}) {
    const auto r = s.sample(e.t_s);
    EXPECT_NEAR(r.position_mm[0], e.x_mm, 1e-12) << e.t_s;
    EXPECT_NEAR(r.position_mm[1], e.y_mm, 1e-12) << e.t_s;
    EXPECT_NEAR(r.position_mm[2], e.z_mm, 1e-12) << e.t_s;
    const Eigen::Quaterniond q = quaternion(r.orientation_wxyz);
    EXPECT_NEAR(base.angularDistance(q) / kDeg, e.tilt_deg, 1e-6) << e.t_s;
    // the tilt is about probe y (scene x): the beam leans toward +z in the organ's y-z plane
    const Eigen::Vector3d beam = q * Eigen::Vector3d::UnitZ();
    const double a = e.tilt_deg * kDeg;
    EXPECT_NEAR((beam - Eigen::Vector3d(0, std::cos(a), std::sin(a))).norm(), 0, 1e-6) << e.t_s;
    EXPECT_EQ(r.depth_mm, e.t_s >= 3.5 && e.t_s < 9.0 ? 80.0 : 0.0) << e.t_s;
    EXPECT_EQ(r.buttons, 0);
  }
}

}  // namespace
}  // namespace pcisim::clients
