#include "png/png_gray.h"

#include <fmt/format.h>
#include <png.h>
#include <zlib.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace pcisim::png {
namespace {

// one image of `channels` samples per pixel (1 grey, 3 RGB), `bits` per sample; row(r, out) fills
// row r as PNG stores it
// how hard zlib works: kDefault (libpng's level and adaptive filters, smallest files), or fast
// ones measured on 512^2 frames of this machine: 16-bit noisy frames with the Sub filter and
// Huffman-only coding take 14 ms and 458 kB against 32 ms and 460 kB for level 1 with every
// filter tried; sparse 8-bit label images with run-length coding a fraction of a millisecond
enum class Effort { kDefault, kFastNoisy, kFastSparse };

// the image's rows through libpng on a write struct already pointed at its output (a file or
// memory); false when libpng reported an error
template <class RowFn>
bool encode_rows(png_structp png, png_infop info, int width, int height, int channels, int bits, Effort effort,
                 RowFn& row_of, std::vector<uint8_t>& row) {
  if (!png || !info || setjmp(png_jmpbuf(png))) return false;
  png_set_IHDR(png, info, width, height, bits, channels == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (effort != Effort::kDefault) {
    png_set_compression_level(png, 1);
    png_set_filter(png, 0, effort == Effort::kFastNoisy ? PNG_FILTER_SUB : PNG_FILTER_NONE);
    png_set_compression_strategy(png, effort == Effort::kFastNoisy ? Z_HUFFMAN_ONLY : Z_RLE);
  }
  png_write_info(png, info);
  for (int r = 0; r < height; ++r) {
    row_of(r, row.data());
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  return true;
}

template <class RowFn>
void write_image(const std::string& path, int width, int height, int channels, int bits, Effort effort, RowFn row_of) {
  if (width <= 0 || height <= 0) throw std::runtime_error(fmt::format("{}: empty image ({}x{})", path, width, height));
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error(fmt::format("{}: cannot write: {}", path, std::strerror(errno)));
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  std::vector<uint8_t> row(static_cast<size_t>(width) * channels * bits / 8);
  if (png) png_init_io(png, f);
  const bool ok = encode_rows(png, info, width, height, channels, bits, effort, row_of, row);
  png_destroy_write_struct(&png, &info);
  // the error of whichever step failed first: on NFS a full quota shows only at close
  const bool flushed = std::fflush(f) == 0 && !std::ferror(f);
  int saved = flushed ? 0 : errno;
  const bool closed = std::fclose(f) == 0;
  if (!closed && saved == 0) saved = errno;
  if (!ok || !flushed || !closed)
    throw std::runtime_error(fmt::format("{}: writing the PNG failed: {}", path, std::strerror(saved ? saved : EIO)));
}

void append_to_vector(png_structp png, png_bytep data, png_size_t length) {
  auto* out = static_cast<std::vector<uint8_t>*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + length);
}

// rows of a grey PNG of `bits` per sample, as stored (16-bit big-endian)
std::vector<uint8_t> read_image(const std::string& path, int bits, int* width, int* height) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error(fmt::format("{}: cannot read: {}", path, std::strerror(errno)));
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  std::vector<uint8_t> data;
  std::string error;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    error = "not a readable PNG";
  } else {
    png_init_io(png, f);
    png_read_info(png, info);
    const int w = static_cast<int>(png_get_image_width(png, info)),
              h = static_cast<int>(png_get_image_height(png, info));
    if (png_get_color_type(png, info) != PNG_COLOR_TYPE_GRAY || png_get_bit_depth(png, info) != bits ||
        png_get_interlace_type(png, info) != PNG_INTERLACE_NONE) {
      error = fmt::format("expected a {}-bit grey PNG", bits);
    } else {
      const size_t row = static_cast<size_t>(w) * bits / 8;
      data.resize(row * h);
      for (int r = 0; r < h; ++r) png_read_row(png, data.data() + row * r, nullptr);
      *width = w;
      *height = h;
    }
  }
  png_destroy_read_struct(&png, &info, nullptr);
  std::fclose(f);
  if (!error.empty()) throw std::runtime_error(fmt::format("{}: {}", path, error));
  return data;
}

}  // namespace

void read_png_gray16(const std::string& path, int* width, int* height, std::vector<uint16_t>* pixels) {
  const std::vector<uint8_t> raw = read_image(path, 16, width, height);
  pixels->resize(raw.size() / 2);
  for (size_t i = 0; i < pixels->size(); ++i) (*pixels)[i] = static_cast<uint16_t>(raw[2 * i] << 8 | raw[2 * i + 1]);
}

void read_png_gray8(const std::string& path, int* width, int* height, std::vector<uint8_t>* pixels) {
  *pixels = read_image(path, 8, width, height);
}

void write_png_gray16(const std::string& path, int width, int height, const uint16_t* pixels, bool fast) {
  // png stores 16-bit samples big-endian
  write_image(path, width, height, 1, 16, fast ? Effort::kFastNoisy : Effort::kDefault, [&](int r, uint8_t* out) {
    const uint16_t* src = pixels + static_cast<size_t>(r) * width;
    for (int c = 0; c < width; ++c) {
      out[2 * c] = static_cast<uint8_t>(src[c] >> 8);
      out[2 * c + 1] = static_cast<uint8_t>(src[c] & 0xff);
    }
  });
}

void write_png_gray8(const std::string& path, int width, int height, const uint8_t* pixels, bool fast) {
  write_image(path, width, height, 1, 8, fast ? Effort::kFastSparse : Effort::kDefault, [&](int r, uint8_t* out) {
    std::memcpy(out, pixels + static_cast<size_t>(r) * width, static_cast<size_t>(width));
  });
}

std::vector<uint8_t> encode_png_rgb8(int width, int height, const uint8_t* rgb) {
  if (width <= 0 || height <= 0) throw std::runtime_error(fmt::format("empty image ({}x{})", width, height));
  std::vector<uint8_t> out;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  std::vector<uint8_t> row(static_cast<size_t>(width) * 3);
  if (png) png_set_write_fn(png, &out, append_to_vector, nullptr);
  auto row_of = [&](int r, uint8_t* dst) { std::memcpy(dst, rgb + static_cast<size_t>(r) * width * 3, row.size()); };
  const bool ok = encode_rows(png, info, width, height, 3, 8, Effort::kDefault, row_of, row);
  png_destroy_write_struct(&png, &info);
  if (!ok) throw std::runtime_error("encoding the PNG failed");
  return out;
}

void write_png_rgb8(const std::string& path, int width, int height, const uint8_t* rgb) {
  write_image(path, width, height, 3, 8, Effort::kDefault, [&](int r, uint8_t* out) {
    std::memcpy(out, rgb + static_cast<size_t>(r) * width * 3, static_cast<size_t>(width) * 3);
  });
}

}  // namespace pcisim::png
