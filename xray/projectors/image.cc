#include "xray/projectors/image.h"

#include <algorithm>

namespace pcisim::xray {

void upsample_bilinear(const Image& coarse, int stride, Image* fine, bool add) {
  const int s = stride, cw = coarse.width, ch = coarse.height;
  for (int r = 0; r < fine->height; ++r) {
    const float y = std::clamp((r - 0.5f * (s - 1)) / s, 0.0f, float(ch - 1));
    const int y0 = std::min(static_cast<int>(y), std::max(ch - 2, 0)), y1 = std::min(y0 + 1, ch - 1);
    const float fy = y - y0;
    for (int c = 0; c < fine->width; ++c) {
      const float x = std::clamp((c - 0.5f * (s - 1)) / s, 0.0f, float(cw - 1));
      const int x0 = std::min(static_cast<int>(x), std::max(cw - 2, 0)), x1 = std::min(x0 + 1, cw - 1);
      const float fx = x - x0;
      const float a = coarse.at(x0, y0) + fx * (coarse.at(x1, y0) - coarse.at(x0, y0));
      const float b = coarse.at(x0, y1) + fx * (coarse.at(x1, y1) - coarse.at(x0, y1));
      float& out = fine->at(c, r);
      out = (add ? out : 0.0f) + (a + fy * (b - a));
    }
  }
}

}  // namespace pcisim::xray
