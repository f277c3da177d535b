#include "modeling/picture/label_placement.h"

#include <gtest/gtest.h>

#include <set>

#include "modeling/picture/tiny_font.h"

namespace pcisim::modeling {
namespace {

// every placed box inside the picture, none over another, each the size of its text
void expect_readable(const std::vector<Label>& labels, const std::vector<PlacedLabel>& placed, int w, int h) {
  for (size_t a = 0; a < placed.size(); ++a) {
    const LabelBox& b = placed[a].box;
    EXPECT_GE(b.x, 0);
    EXPECT_GE(b.y, 0);
    EXPECT_LE(b.x + b.w, w);
    EXPECT_LE(b.y + b.h, h);
    EXPECT_EQ(b.w, text_width(labels[placed[a].label].text) + 2);
    for (size_t c = a + 1; c < placed.size(); ++c)
      EXPECT_FALSE(b.overlaps(placed[c].box))
          << labels[placed[a].label].text << " over " << labels[placed[c].label].text;
  }
}

TEST(LabelPlacement, ALoneLabelSitsBesideItsAnchor) {
  const std::vector<Label> labels = {{"LAD", 100, 50, 1}};
  const auto placed = place_labels(labels, 300, 200);
  ASSERT_EQ(placed.size(), 1u);
  EXPECT_FALSE(placed[0].moved);
  EXPECT_EQ(placed[0].box.x, 103);  // just right of the vessel's end
  EXPECT_LE(std::abs(placed[0].box.y + placed[0].box.h / 2 - 47), 1);
}

// the overview's old failure: a dozen branch ends within a few pixels, every label at its end,
// piled up unreadably. Now none covers another, the trunks keep their spots beside their ends.
TEST(LabelPlacement, CrowdedEndsGetBoxesThatDoNotOverlap) {
  std::vector<Label> labels;
  const char* names[] = {"OM1", "OM2", "OM3", "D1", "D2", "D3", "LCX", "SB1", "SB2", "OM4", "D4", "LAD"};
  for (int n = 0; n < 12; ++n) labels.push_back({names[n], 120 + (n % 4) * 3, 80 + (n / 4) * 2, n >= 10 ? 100 : 50});
  std::vector<size_t> dropped;
  const auto placed = place_labels(labels, 400, 300, &dropped);
  expect_readable(labels, placed, 400, 300);
  EXPECT_EQ(placed.size() + dropped.size(), labels.size());
  EXPECT_EQ(placed.size(), labels.size());  // room enough around them
  // the two of priority 100 were placed first: beside their ends
  std::set<std::string> first;
  for (size_t n = 0; n < 2; ++n) first.insert(labels[placed[n].label].text);
  EXPECT_EQ(first, (std::set<std::string>{"D4", "LAD"}));
}

TEST(LabelPlacement, NoRoomLeavesALabelOutRatherThanOverAnother) {
  // a picture just wide enough for one label: the second cannot be placed anywhere
  std::vector<Label> labels = {{"RCA", 5, 8, 2}, {"LCX", 6, 8, 1}};
  std::vector<size_t> dropped;
  const auto placed = place_labels(labels, 30, 16, &dropped);
  expect_readable(labels, placed, 30, 16);
  ASSERT_EQ(placed.size(), 1u);
  EXPECT_EQ(labels[placed[0].label].text, "RCA");
  ASSERT_EQ(dropped.size(), 1u);
  EXPECT_EQ(labels[dropped[0]].text, "LCX");
}

}  // namespace
}  // namespace pcisim::modeling
