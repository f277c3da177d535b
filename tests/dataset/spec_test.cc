// The dataset spec: every key checked like a scene, a bad one refused naming it; distributions
// stay in their ranges and draw the same values from the same seed.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "dataset/sample/sample_plan.h"
#include "dataset/spec/dataset_spec.h"
#include "dataset/spec/distribution.h"
#include "json/json_reader.h"

namespace pcisim::dataset {
namespace {

// the error parse_dataset_spec throws for `text`, "" when it is accepted
std::string refusal(const std::string& text) {
  try {
    parse_dataset_spec(text, "s.json", "");
  } catch (const json::JsonError& e) {
    return e.what();
  }
  return "";
}

TEST(DatasetSpec, AMinimalSpecTakesTheBuiltInScene) {
  const DatasetSpec s = parse_dataset_spec(R"({"samples": 4})", "s.json", "");
  EXPECT_EQ(s.samples, 4);
  EXPECT_EQ(s.scene_source, "built-in");
  EXPECT_EQ(s.frames_per_sample, 10);
  EXPECT_TRUE(s.vary.empty());
}

TEST(DatasetSpec, ABadSpecIsRefusedNamingTheKey) {
  // unknown key, missing count, a distribution written wrong, a value out of its range
  EXPECT_NE(refusal(R"({"samples": 4, "sampels": 5})").find("sampels"), std::string::npos);
  EXPECT_NE(refusal(R"({})").find("samples"), std::string::npos);
  EXPECT_NE(refusal(R"({"samples": 0})").find("samples"), std::string::npos);
  EXPECT_NE(refusal(R"({"samples": 2, "warmup_s": {"uniform": [3, 1]}})").find("warmup_s.uniform"), std::string::npos);
  EXPECT_NE(refusal(R"({"samples": 2, "driver": {"kind": "joystick"}})").find("driver.kind"), std::string::npos);
  EXPECT_NE(refusal(R"({"samples": 2, "driver": {"insert_rate_mm_s": {"normal": [0, 1]}}})").find("normal"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"samples": 2, "anatomy": {"cases": ["/nonexistent/case"]}})").find("anatomy.cases"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"samples": 2, "scene": "/nonexistent/scene.json"})").find("scene"), std::string::npos);
}

TEST(DatasetSpec, AVariedValueIsCheckedByTheSceneAtItsExtremes) {
  // a key the scene does not have, and a range whose end the scene refuses: both named
  const std::string typo = refusal(R"({"samples": 2, "vary": {"effects.xray.primry_deg": 10}})");
  EXPECT_NE(typo.find("vary.effects.xray.primry_deg"), std::string::npos) << typo;
  const std::string range = refusal(R"({"samples": 2, "vary": {"effects.xray.primary_deg": {"uniform": [-200, 0]}}})");
  EXPECT_NE(range.find("vary.effects.xray.primary_deg = -200"), std::string::npos) << range;
  EXPECT_NE(range.find("primary_deg"), std::string::npos);
  const std::string choice =
      refusal(R"({"samples": 2, "vary": {"effects.xray.pulse_rate_fps": {"choice": [15, 25]}}})");
  EXPECT_NE(choice.find("pulse_rate_fps = 25"), std::string::npos) << choice;
  // the anatomy is drawn by its own key, and a dataset needs fluoroscopy
  EXPECT_NE(refusal(R"({"samples": 2, "vary": {"anatomy.phantom_seed": 3}})").find("vary.anatomy"), std::string::npos);
}

TEST(Distribution, DrawsStayInRangeAndRepeatFromTheSeed) {
  const Distribution u = Distribution::parse({{"uniform", {-2.0, 3.0}}}, "u");
  const Distribution l = Distribution::parse({{"log_uniform", {10.0, 1000.0}}}, "l");
  const Distribution n = Distribution::parse({{"integers", {1, 4}}}, "n");
  const Distribution c = Distribution::parse({{"choice", {"a", "b"}}}, "c");
  SampleRng a(7), b(7);
  std::set<int64_t> ints;
  std::set<std::string> picks;
  for (int i = 0; i < 400; ++i) {
    const double x = u.draw_number(a), y = l.draw_number(a);
    EXPECT_GE(x, -2.0);
    EXPECT_LT(x, 3.0);
    EXPECT_GE(y, 10.0 * (1 - 1e-12));
    EXPECT_LE(y, 1000.0 * (1 + 1e-12));
    ints.insert(n.draw(a).get<int64_t>());
    picks.insert(c.draw(a).get<std::string>());
    EXPECT_EQ(x, u.draw_number(b));
    EXPECT_EQ(y, l.draw_number(b));
    n.draw(b), c.draw(b);
  }
  EXPECT_EQ(ints, (std::set<int64_t>{1, 2, 3, 4}));
  EXPECT_EQ(picks, (std::set<std::string>{"a", "b"}));
  // a plain value is fixed
  SampleRng r(1);
  EXPECT_EQ(Distribution::parse(42, "f").draw(r), 42);
}

TEST(SamplePlan, ASampleDrawsTheSameOnEveryShardAndDiffersFromItsNeighbours) {
  const DatasetSpec s = parse_dataset_spec(
      R"({"samples": 10, "seed": 3, "anatomy": {"phantom_seeds": {"integers": [1, 3]}},
          "vary": {"effects.xray.primary_deg": {"uniform": [-40, 40]}}})",
      "s.json", "");
  const SamplePlan a = plan_sample(s, 5), b = plan_sample(s, 5), c = plan_sample(s, 6);
  EXPECT_EQ(a.drawn, b.drawn);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_NE(a.drawn, c.drawn);
  EXPECT_NE(a.seed, c.seed);
  // the drawn value reaches the scene the sample runs
  EXPECT_DOUBLE_EQ(a.scene.xray->initial_pose.primary_deg, a.drawn["vary"]["effects.xray.primary_deg"].get<double>());
  const auto seed = a.drawn["anatomy"]["phantom_seed"].get<uint32_t>();
  EXPECT_EQ(a.scene.world.anatomy.seed, seed);
  EXPECT_GE(seed, 1u);
  EXPECT_LE(seed, 3u);
}

}  // namespace
}  // namespace pcisim::dataset
