#pragma once
// Grey PNG files (libpng): 16-bit frames, the format labelled fluoroscopy datasets keep, and 8-bit
// pictures for people. The one PNG writer of pcisim: the X-ray tools, the capture client and the
// case overviews use it.
#include <cstdint>
#include <string>
#include <vector>

namespace pcisim::png {

// pixels row-major, row 0 first. Throws std::runtime_error naming the path and the reason.
// fast: zlib level 1 (frames arrive at up to 30 per second)
void write_png_gray16(const std::string& path, int width, int height, const uint16_t* pixels, bool fast = true);
// fast: for label images, mostly runs of one value (run-length coding, level 1)
void write_png_gray8(const std::string& path, int width, int height, const uint8_t* pixels, bool fast = false);
// colour pictures for people: 3 bytes (R, G, B) per pixel, row-major
// reads a grey PNG of exactly that depth (what the writers above make), for tests and tools.
// Throws std::runtime_error naming the path and the reason (missing, not PNG, other format)
void read_png_gray16(const std::string& path, int* width, int* height, std::vector<uint16_t>* pixels);
void read_png_gray8(const std::string& path, int* width, int* height, std::vector<uint8_t>* pixels);
void write_png_rgb8(const std::string& path, int width, int height, const uint8_t* rgb);
// the same picture as the bytes of a PNG file (to embed in a page); throws std::runtime_error
std::vector<uint8_t> encode_png_rgb8(int width, int height, const uint8_t* rgb);

}  // namespace pcisim::png
