#include "clients/bridge/trainee_script.h"

#include <gtest/gtest.h>

#include <numbers>

#include "pcisim_lcm/instrument_state_t.hpp"

namespace pcisim::clients {
namespace {

std::string error_of(const std::string& text) {
  try {
    TraineeScript::parse(text, "s.json");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(TraineeScript, RampsAddUpAndReportTheirRates) {
  const auto s = TraineeScript::parse(R"({"actions": [
      {"at_s": 1, "do": "insert", "mm": 10, "over_s": 2},
      {"at_s": 2, "do": "rotate", "deg": 180, "over_s": 1},
      {"at_s": 4, "do": "pull", "mm": 4, "over_s": 1}]})",
                                      "s");
  EXPECT_DOUBLE_EQ(s.sample(0.5).insertion_mm, 0.0);
  const auto mid = s.sample(2.5);
  EXPECT_DOUBLE_EQ(mid.insertion_mm, 7.5);
  EXPECT_DOUBLE_EQ(mid.insertion_rate_mm_s, 5.0);
  EXPECT_DOUBLE_EQ(mid.rotation_rad, std::numbers::pi / 2);
  EXPECT_DOUBLE_EQ(mid.rotation_rate_rad_s, std::numbers::pi);
  EXPECT_DOUBLE_EQ(s.sample(3.5).insertion_rate_mm_s, 0.0);
  EXPECT_DOUBLE_EQ(s.sample(10).insertion_mm, 6.0);
  EXPECT_DOUBLE_EQ(s.duration_s(), 5.0);
}

TEST(TraineeScript, PedalHoldsUntilReleasedAndContrastForItsDuration) {
  using I = pcisim_lcm::instrument_state_t;
  const auto s = TraineeScript::parse(R"({"actions": [
      {"at_s": 1, "do": "pedal", "down": true},
      {"at_s": 2, "do": "contrast", "for_s": 1},
      {"at_s": 4, "do": "pedal", "down": false}]})",
                                      "s");
  EXPECT_EQ(s.sample(0.5).buttons, 0);
  EXPECT_EQ(s.sample(1.5).buttons, I::BUTTON_FLUORO_PEDAL);
  EXPECT_EQ(s.sample(2.5).buttons, int{I::BUTTON_FLUORO_PEDAL} | int{I::BUTTON_CONTRAST});
  EXPECT_EQ(s.sample(3.5).buttons, I::BUTTON_FLUORO_PEDAL);
  EXPECT_EQ(s.sample(4.5).buttons, 0);
}

TEST(TraineeScript, BuiltInScriptParsesAndLastsAboutTwentySeconds) {
  const auto s = TraineeScript::parse(TraineeScript::builtin_text(), "built-in");
  EXPECT_GT(s.duration_s(), 15.0);
  EXPECT_LE(s.duration_s(), 20.0);
  EXPECT_GT(s.sample(s.duration_s()).insertion_mm, 20.0);
}

TEST(TraineeScript, BadScriptsNameThePath) {
  EXPECT_EQ(error_of(R"({"actions": [{"at_s": 1, "do": "jump"}]})"),
            "s.json: actions[0].do: expected one of \"insert\", \"pull\", \"rotate\", \"pedal\", \"cine\", "
            "\"contrast\", got \"jump\"");
  EXPECT_EQ(error_of(R"({"actions": [{"at_s": 1, "do": "insert", "mm": 5, "speed": 2}]})"),
            "s.json: actions[0].speed: unknown key (this object accepts: at_s, do, mm, over_s)");
  EXPECT_EQ(error_of(R"({"actions": [{"at_s": -1, "do": "insert"}]})"),
            "s.json: actions[0].at_s: expected a number in [0, 1000000], got -1");
  EXPECT_EQ(error_of(R"({"actions": []})"), "s.json: actions: expected at least one action");
  EXPECT_EQ(error_of(R"({"actions": 3})"), "s.json: actions: expected a list, got 3");
  EXPECT_NE(error_of("{").find("s.json: not valid JSON"), std::string::npos);
}

}  // namespace
}  // namespace pcisim::clients
