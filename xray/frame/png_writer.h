#pragma once
// 8-bit grey PNG previews of line-integral images, for people (the float image is the data).
#include <cstdint>
#include <string>
#include <vector>

#include "xray/projectors/image.h"

namespace pcisim::xray {

// true when this build links libpng
bool png_supported();

// writes the image as 8-bit grey in the look of a fluoroscopy frame: attenuation dark,
// 255 (1 - (L - L_lo) / (L_hi - L_lo)) clamped, L_lo and L_hi the 0.5th and 99.5th percentiles. False with a reason
// when libpng is missing or the file cannot be written.
bool write_png_preview(const Image& image, const std::string& path, std::string* error);

// writes a display frame (uint16 grey, row-major, row 0 first, as the fluoroscopy renderer
// makes it) as a 16-bit grey PNG, unchanged; false with a reason when it cannot
bool write_png_gray16(int width, int height, const std::vector<uint16_t>& pixels, const std::string& path,
                      std::string* error);

}  // namespace pcisim::xray
