#include "modeling/picture/label_placement.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "modeling/picture/tiny_font.h"

namespace pcisim::modeling {

std::vector<PlacedLabel> place_labels(const std::vector<Label>& labels, int width, int height,
                                      std::vector<size_t>* dropped) {
  std::vector<size_t> order(labels.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return labels[a].priority > labels[b].priority; });
  // rings of candidate spots: right of the anchor first (where the text reads on from the
  // vessel's end), then around it at 12 angles per ring
  constexpr int kRings[] = {0, 10, 18, 28, 40, 56};
  std::vector<PlacedLabel> placed;
  for (size_t n : order) {
    const Label& l = labels[n];
    const int w = text_width(l.text) + 2, h = 9;
    bool done = false;
    for (int ring : kRings) {
      const int spots = ring == 0 ? 1 : 12;
      for (int s = 0; s < spots && !done; ++s) {
        const double a = 2.0 * 3.14159265358979 * s / spots;
        // the box's near edge at the ring: to the right its left edge, to the left its right edge
        const int cx = l.anchor_x + static_cast<int>(std::lround(ring * std::cos(a)));
        const int cy = l.anchor_y - static_cast<int>(std::lround(ring * std::sin(a)));
        LabelBox b{std::cos(a) >= -1e-9 ? cx + 3 : cx - 3 - w, cy - h / 2 - 3, w, h};
        if (b.x < 0 || b.y < 0 || b.x + b.w > width || b.y + b.h > height) continue;
        bool free = true;
        for (const PlacedLabel& p : placed) free = free && !b.overlaps(p.box);
        if (!free) continue;
        placed.push_back({n, b, ring > 0});
        done = true;
      }
      if (done) break;
    }
    if (!done && dropped) dropped->push_back(n);
  }
  return placed;
}

}  // namespace pcisim::modeling
