#include "clients/capture/png16.h"

#include <png.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fmt/format.h>
#include <stdexcept>
#include <vector>

namespace pcisim::clients {

void write_png16(const std::string& path, int width, int height, const uint16_t* pixels) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error(fmt::format("{}: cannot write: {}", path, std::strerror(errno)));
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  // png stores 16-bit samples big-endian
  std::vector<uint8_t> row(static_cast<size_t>(width) * 2);
  bool ok = png && info && !setjmp(png_jmpbuf(png));
  if (ok) {
    png_init_io(png, f);
    png_set_IHDR(png, info, width, height, 16, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, 1);  // fast: frames arrive at up to 30 per second
    png_write_info(png, info);
    for (int r = 0; r < height; ++r) {
      const uint16_t* src = pixels + static_cast<size_t>(r) * width;
      for (int c = 0; c < width; ++c) {
        row[2 * c] = static_cast<uint8_t>(src[c] >> 8);
        row[2 * c + 1] = static_cast<uint8_t>(src[c] & 0xff);
      }
      png_write_row(png, row.data());
    }
    png_write_end(png, nullptr);
  }
  png_destroy_write_struct(&png, &info);
  const bool flushed = std::fflush(f) == 0 && !std::ferror(f);
  const int saved = errno;
  const bool closed = std::fclose(f) == 0;
  if (!ok || !flushed || !closed)
    throw std::runtime_error(fmt::format("{}: writing the PNG failed: {}", path, std::strerror(saved ? saved : EIO)));
}

}  // namespace pcisim::clients
