#pragma once
// A 5 x 7 pixel font for labels on pictures (upper-case letters, digits, a few signs; lower case
// is drawn as upper case, anything else as a blank).
#include <cstdint>
#include <string_view>

namespace pcisim::modeling {

// the 7 rows of a character, bit 4 the leftmost column
const uint8_t* tiny_glyph(char c);

// draws text with its top-left corner at (x, y), each font pixel `scale` x `scale`, into an RGB
// image of width w and height h (pixels outside are skipped)
void draw_text(uint8_t* rgb, int w, int h, int x, int y, std::string_view text, const uint8_t color[3], int scale = 1);

// the width in pixels draw_text takes
inline int text_width(std::string_view text, int scale = 1) {
  return static_cast<int>(text.size()) * 6 * scale;
}

}  // namespace pcisim::modeling
