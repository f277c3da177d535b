#pragma once
// A detector image of float line integrals, row-major, row 0 first. Sized once by the caller;
// projectors write into it and never allocate.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pcisim::xray {

struct Image {
  int width = 0, height = 0;
  std::vector<float> pixels;

  void resize(int w, int h) {
    width = w;
    height = h;
    pixels.assign(static_cast<size_t>(w) * h, 0.0f);
  }
  float& at(int c, int r) { return pixels[static_cast<size_t>(r) * width + c]; }
  float at(int c, int r) const { return pixels[static_cast<size_t>(r) * width + c]; }
};

}  // namespace pcisim::xray
