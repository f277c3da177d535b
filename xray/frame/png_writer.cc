#include "xray/frame/png_writer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#ifdef PCISIM_XRAY_HAVE_PNG
#include "png/png_gray.h"
#include "realtime/percentile.h"
#endif

namespace pcisim::xray {

bool png_supported() {
#ifdef PCISIM_XRAY_HAVE_PNG
  return true;
#else
  return false;
#endif
}

bool write_png_preview(const Image& image, const std::string& path, std::string* error) {
#ifndef PCISIM_XRAY_HAVE_PNG
  (void)image, (void)path;
  *error = "this build has no libpng";
  return false;
#else
  // window: the 0.5th to 99.5th percentile of the line integrals, so bone and air do not
  // squeeze the contrast-filled vessels into a few grey levels
  std::vector<float> sorted = image.pixels;
  if (sorted.empty()) {
    *error = path + ": empty image";
    return false;
  }
  const float lo = realtime::percentile_in_place(std::span<float>(sorted), 0.005);
  const float hi = realtime::percentile_in_place(std::span<float>(sorted), 0.995);
  const float scale = hi > lo ? 1.f / (hi - lo) : 0.f;
  std::vector<uint8_t> grey(image.pixels.size());
  for (size_t n = 0; n < grey.size(); ++n) {
    grey[n] = static_cast<uint8_t>(std::lround(255.f * std::clamp(1.f - (image.pixels[n] - lo) * scale, 0.f, 1.f)));
  }
  try {
    png::write_png_gray8(path, image.width, image.height, grey.data());
  } catch (const std::runtime_error& e) {
    *error = e.what();
    return false;
  }
  return true;
#endif
}

bool write_png_gray16(int width, int height, const std::vector<uint16_t>& pixels, const std::string& path,
                      std::string* error) {
#ifndef PCISIM_XRAY_HAVE_PNG
  (void)width, (void)height, (void)pixels, (void)path;
  *error = "this build has no libpng";
  return false;
#else
  if (width <= 0 || height <= 0 || pixels.size() != static_cast<size_t>(width) * height) {
    *error = path + ": pixel count does not match the frame size";
    return false;
  }
  try {
    png::write_png_gray16(path, width, height, pixels.data(), /*fast=*/false);
  } catch (const std::runtime_error& e) {
    *error = e.what();
    return false;
  }
  return true;
#endif
}

}  // namespace pcisim::xray
