#pragma once
// 16-bit greyscale PNG files (libpng), the format labelled fluoroscopy datasets keep.
#include <cstdint>
#include <string>

namespace pcisim::clients {

// throws std::runtime_error naming the path and the reason when the file cannot be written
void write_png16(const std::string& path, int width, int height, const uint16_t* pixels);

}  // namespace pcisim::clients
