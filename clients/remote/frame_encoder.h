#pragma once
// Turns a frame into what a browser can show: a 16-bit fluoroscopy frame through a display window
// to 8 bits, an 8-bit ultrasound frame as it is; then JPEG (small, fast) or PNG (lossless). The
// result is the whole WebSocket message, encoded once and shared by every connection; its header's
// `kind` says which modality it is.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "pcisim_lcm/us_frame_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"

namespace pcisim::remote {

enum class ImageFormat { kJpeg, kPng };

struct EncoderOptions {
  ImageFormat format = ImageFormat::kJpeg;
  int jpeg_quality = 85;
  int window_lo = 0, window_hi = 65535;  // 16-bit values mapped to black and white
};

// binary message: uint32 little-endian n, n bytes of JSON header, then the image file
struct EncodedFrame {
  std::string message;
  int64_t seq = 0;
  size_t image_bytes = 0;
};

class FrameEncoder {
 public:
  explicit FrameEncoder(const EncoderOptions& options);
  ~FrameEncoder();
  FrameEncoder(const FrameEncoder&) = delete;
  FrameEncoder& operator=(const FrameEncoder&) = delete;

  // throws std::runtime_error on a frame it cannot show (bad size or format)
  std::shared_ptr<const EncodedFrame> encode(const pcisim_lcm::xray_frame_t& frame);
  std::shared_ptr<const EncodedFrame> encode(const pcisim_lcm::us_frame_t& frame);
  const char* mime() const;

 private:
  void window(const pcisim_lcm::xray_frame_t& frame);
  // the message: the header, then gray_ (width x height) as an image file
  std::shared_ptr<const EncodedFrame> finish(const nlohmann::json& header, int64_t seq, int width, int height);
  void encode_jpeg(int width, int height, std::string& out);
  void encode_png(int width, int height, std::string& out);

  EncoderOptions options_;
  std::vector<uint8_t> gray_;  // reused: no allocation per frame once sized
  void* jpeg_ = nullptr;       // tjhandle
};

// 16-bit value to 8 bits through the window [lo, hi]
inline uint8_t window_to_8bit(uint16_t v, int lo, int hi) {
  if (v <= lo) return 0;
  if (v >= hi) return 255;
  return static_cast<uint8_t>((static_cast<int64_t>(v - lo) * 255 + (hi - lo) / 2) / (hi - lo));
}

}  // namespace pcisim::remote
