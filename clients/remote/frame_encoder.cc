#include "clients/remote/frame_encoder.h"

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <png.h>
#include <stdexcept>
#include <turbojpeg.h>

#include "protocol/us_frame_geometry.h"

namespace pcisim::remote {

FrameEncoder::FrameEncoder(const EncoderOptions& options) : options_(options) {
  if (options_.window_hi <= options_.window_lo) throw std::invalid_argument("display window: hi must exceed lo");
  if (options_.format == ImageFormat::kJpeg) {
    jpeg_ = tjInitCompress();
    if (!jpeg_) throw std::runtime_error("turbojpeg: cannot create a compressor");
  }
}

FrameEncoder::~FrameEncoder() {
  if (jpeg_) tjDestroy(static_cast<tjhandle>(jpeg_));
}

const char* FrameEncoder::mime() const {
  return options_.format == ImageFormat::kJpeg ? "image/jpeg" : "image/png";
}

void FrameEncoder::window(const pcisim_lcm::xray_frame_t& f) {
  const size_t n = static_cast<size_t>(f.width) * static_cast<size_t>(f.height);
  gray_.resize(n);
  if (f.pixel_format == pcisim_lcm::xray_frame_t::FORMAT_GRAY8) {
    std::memcpy(gray_.data(), f.data.data(), n);
    return;
  }
  const uint8_t* p = f.data.data();
  for (size_t i = 0; i < n; ++i) {
    const uint16_t v = static_cast<uint16_t>(p[2 * i] | (p[2 * i + 1] << 8));  // little-endian on the wire
    gray_[i] = window_to_8bit(v, options_.window_lo, options_.window_hi);
  }
}

void FrameEncoder::encode_jpeg(int width, int height, std::string& out) {
  unsigned char* buf = nullptr;
  unsigned long size = 0;
  if (tjCompress2(static_cast<tjhandle>(jpeg_), gray_.data(), width, 0, height, TJPF_GRAY, &buf, &size, TJSAMP_GRAY,
                  options_.jpeg_quality, TJFLAG_FASTDCT) != 0) {
    if (buf) tjFree(buf);
    throw std::runtime_error(std::string("turbojpeg: ") + tjGetErrorStr2(static_cast<tjhandle>(jpeg_)));
  }
  out.append(reinterpret_cast<const char*>(buf), size);
  tjFree(buf);
}

namespace {
void png_append(png_structp png, png_bytep data, png_size_t n) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), n);
}
void png_no_flush(png_structp) {}
// libpng's errors return by longjmp to encode_png's setjmp (an exception must not unwind through
// libpng's C frames); the message is kept for the exception thrown there
[[noreturn]] void png_fail(png_structp png, png_const_charp msg) {
  *static_cast<std::string*>(png_get_error_ptr(png)) = msg;
  png_longjmp(png, 1);
}
}  // namespace

void FrameEncoder::encode_png(int width, int height, std::string& out) {
  std::string error;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, png_fail, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    throw std::runtime_error("libpng: out of memory");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error("libpng: " + error);
  }
  png_set_write_fn(png, &out, png_append, png_no_flush);
  png_set_IHDR(png, info, width, height, 8, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, 1);  // speed over size: a frame must leave within its pulse
  png_write_info(png, info);
  for (int r = 0; r < height; ++r) png_write_row(png, gray_.data() + static_cast<size_t>(r) * width);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
}

std::shared_ptr<const EncodedFrame> FrameEncoder::encode(const pcisim_lcm::xray_frame_t& f) {
  using X = pcisim_lcm::xray_frame_t;
  const int bytes_per_px = f.pixel_format == X::FORMAT_GRAY16 ? 2 : f.pixel_format == X::FORMAT_GRAY8 ? 1 : 0;
  if (bytes_per_px == 0) throw std::runtime_error("frame: only GRAY8 and GRAY16 frames are shown");
  if (f.width <= 0 || f.height <= 0 || f.width > 8192 || f.height > 8192 ||
      static_cast<int64_t>(f.data.size()) != static_cast<int64_t>(f.width) * f.height * bytes_per_px)
    throw std::runtime_error("frame: size does not match its pixels");
  window(f);

  nlohmann::json h = {{"kind", "xray"},
                      {"seq", f.seq},
                      {"utime", f.utime},
                      {"width", f.width},
                      {"height", f.height},
                      {"mime", mime()},
                      {"primary_deg", f.primary_angle_deg},
                      {"secondary_deg", f.secondary_angle_deg},
                      {"sim_time_s", f.sim_time_s},
                      {"cine", f.cine != 0},
                      {"cine_run", f.cine_run}};
  if (f.num_wire_points > 0 && std::isfinite(f.wire_px.back()[0]))
    h["tip_px"] = {f.wire_px.back()[0], f.wire_px.back()[1]};
  return finish(h, f.seq, f.width, f.height);
}

std::shared_ptr<const EncodedFrame> FrameEncoder::encode(const pcisim_lcm::us_frame_t& f) {
  using U = pcisim_lcm::us_frame_t;
  if (f.pixel_format != U::FORMAT_GRAY8) throw std::runtime_error("ultrasound frame: only GRAY8 frames are shown");
  if (f.width <= 0 || f.height <= 0 || f.width > 8192 || f.height > 8192 ||
      static_cast<int64_t>(f.data.size()) != static_cast<int64_t>(f.width) * f.height)
    throw std::runtime_error("ultrasound frame: size does not match its pixels");
  gray_.assign(f.data.begin(), f.data.end());  // grey levels as the renderer made them: no window

  const bool linear = f.geometry == U::GEOMETRY_LINEAR;
  const protocol::UsImagePlane plane = protocol::us_image_plane(f);
  nlohmann::json h = {{"kind", "ultrasound"},
                      {"seq", f.seq},
                      {"utime", f.utime},
                      {"width", f.width},
                      {"height", f.height},
                      {"mime", mime()},
                      {"sim_time_s", f.sim_time_s},
                      {"geometry", linear ? "linear" : "curvilinear"},
                      {"depth_mm", f.depth_mm},
                      {"gain_db", f.gain_db},
                      {"frequency_mhz", f.frequency_mhz},
                      {"probe_force_n", {f.probe_force_n[0], f.probe_force_n[1], f.probe_force_n[2]}},
                      // the picture's size in the probe's plane: the page keeps its aspect
                      {"image_mm", {plane.width_mm, plane.height_mm}}};
  if (linear) {
    h["width_mm"] = f.width_mm;
  } else {
    h["fan_angle_deg"] = f.fan_angle_deg;
    h["radius_of_curvature_mm"] = f.radius_of_curvature_mm;
  }
  return finish(h, f.seq, f.width, f.height);
}

std::shared_ptr<const EncodedFrame> FrameEncoder::finish(const nlohmann::json& h, int64_t seq, int width, int height) {
  const std::string header = h.dump();
  auto e = std::make_shared<EncodedFrame>();
  e->seq = seq;
  const auto n = static_cast<uint32_t>(header.size());
  e->message.reserve(4 + header.size() + gray_.size() / 4);
  for (int k = 0; k < 4; ++k) e->message += static_cast<char>((n >> (8 * k)) & 0xff);
  e->message += header;
  const size_t before = e->message.size();
  if (options_.format == ImageFormat::kJpeg)
    encode_jpeg(width, height, e->message);
  else
    encode_png(width, height, e->message);
  e->image_bytes = e->message.size() - before;
  return e;
}

}  // namespace pcisim::remote
