// A dataset spec's parse is bounded: the values it tries against the scene up front (each a scene
// parse) are at most kMaxVariedValuesTried, so a spec of long lists is refused at once instead of
// being checked for 18 s (a 390 KB "choice" of 100 000 angles once was). "At once" is asserted by
// order, not by a clock: the list's first value is one the scene refuses, so a parse that tried
// values before counting them would name that value instead of the bound.
#include <gtest/gtest.h>

#include <string>

#include "dataset/spec/dataset_spec.h"
#include "json/json_reader.h"

namespace pcisim::dataset {
namespace {

TEST(DatasetSpecBounds, ALongChoiceIsRefusedAtOnceNamingVary) {
  std::string choice;
  // 1e6 degrees first: the scene would refuse it, were it tried
  for (int i = 0; i < 100'000; ++i) choice += (i ? "," : "") + std::to_string(i ? i % 90 : 1'000'000);
  const std::string text = R"({"samples": 1, "vary": {"effects.xray.primary_deg": {"choice": [)" + choice + "]}}}";
  std::string what;
  try {
    parse_dataset_spec(text, "s.json", "");
  } catch (const json::JsonError& e) {
    what = e.what();
  }
  EXPECT_EQ(what,
            "s.json: vary: expected at most 4096 values to try against the scene (each choice's values, each range's "
            "two ends), got 100000");
}

TEST(DatasetSpecBounds, ManyShortEntriesStayWithinTheBound) {
  // 2 ends x 4 entries: far below the bound, accepted
  const DatasetSpec s = parse_dataset_spec(
      R"({"samples": 1, "vary": {"effects.xray.primary_deg": {"uniform": [-40, 40]},
          "effects.xray.secondary_deg": {"uniform": [-20, 20]}, "effects.xray.sid_mm": {"uniform": [950, 1200]},
          "effects.xray.pulse_rate_fps": {"choice": [7.5, 15, 30]}}})",
      "s.json", "");
  EXPECT_EQ(s.vary.size(), 4u);
}

}  // namespace
}  // namespace pcisim::dataset
