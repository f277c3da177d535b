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

// fine (its size kept) from the image of coarse_detector(fine's detector, stride), bilinear:
// fine pixel c sits at coarse coordinate (c - (s - 1) / 2) / s, clamped at the edges. add: adds
// to fine's pixels instead of writing them
void upsample_bilinear(const Image& coarse, int stride, Image* fine, bool add = false);

}  // namespace pcisim::xray
