#include "xray/frame/png_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#ifdef PCISIM_XRAY_HAVE_PNG
#include <png.h>
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
  auto percentile = [&sorted](double q) {
    const size_t k = std::min(sorted.size() - 1, static_cast<size_t>(q * (sorted.size() - 1)));
    std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
    return sorted[k];
  };
  const float lo = percentile(0.005), hi = percentile(0.995);
  const float scale = hi > lo ? 1.f / (hi - lo) : 0.f;
  std::vector<png_byte> grey(image.pixels.size());
  for (size_t n = 0; n < grey.size(); ++n) {
    grey[n] = static_cast<png_byte>(std::lround(255.f * std::clamp(1.f - (image.pixels[n] - lo) * scale, 0.f, 1.f)));
  }
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) {
    *error = path + ": cannot open for writing";
    return false;
  }
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
    *error = path + ": libpng failed";
    return false;
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int r = 0; r < image.height; ++r) png_write_row(png, grey.data() + static_cast<size_t>(r) * image.width);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return std::fclose(f) == 0;
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
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) {
    *error = path + ": cannot open for writing";
    return false;
  }
  // PNG stores 16-bit samples big-endian
  std::vector<png_byte> row(static_cast<size_t>(width) * 2);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
    *error = path + ": libpng failed";
    return false;
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, width, height, 16, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const uint16_t v = pixels[static_cast<size_t>(r) * width + c];
      row[2 * c] = static_cast<png_byte>(v >> 8);
      row[2 * c + 1] = static_cast<png_byte>(v & 0xff);
    }
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return std::fclose(f) == 0;
#endif
}

}  // namespace pcisim::xray
