#pragma once
// Labels that do not cover each other: each label's box is put near its anchor (a branch's far
// end), the most important first, on the first free spot of rings of growing radius around it;
// a label with no free spot within the largest ring is left out (and listed), never drawn over
// another. The overview (model_overview.h) draws a leader line to a label moved off its anchor.
#include <cstddef>
#include <string>
#include <vector>

namespace pcisim::modeling {

struct LabelBox {
  int x = 0, y = 0, w = 0, h = 0;  // top-left corner and size, pixels
  bool overlaps(const LabelBox& o) const { return x < o.x + o.w && o.x < x + w && y < o.y + o.h && o.y < y + h; }
};

struct Label {
  std::string text;
  int anchor_x = 0, anchor_y = 0;
  int priority = 0;  // higher is placed first
};

struct PlacedLabel {
  size_t label = 0;  // index into the labels given
  LabelBox box;
  bool moved = false;  // off the spot next to its anchor: draw a leader line
};

// boxes text_width(text) + 2 wide and 9 tall (tiny_font.h), inside [0, width) x [0, height);
// `dropped` (may be null) receives the labels left out
std::vector<PlacedLabel> place_labels(const std::vector<Label>& labels, int width, int height,
                                      std::vector<size_t>* dropped = nullptr);

}  // namespace pcisim::modeling
