// Ultrasound frames through pcisim-capture's LCM side: published on the image bus (memq) beside
// X-ray frames, each good one lands as an 8-bit PNG whose pixels are the message's bytes, with a
// sidecar holding the probe's geometry; a bad one is counted and leaves no file.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <png.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <numbers>

#include "clients/capture/capture_sink.h"
#include "clients/capture/frame_writer.h"
#include "protocol/channels.h"

namespace pcisim::clients {
namespace {

namespace fs = std::filesystem;
using F = pcisim_lcm::us_frame_t;

// a 48 x 32 frame whose every pixel differs from its neighbours, probe on the anterior face
F us_frame(int64_t seq, int8_t geometry = F::GEOMETRY_LINEAR) {
  F f{};
  f.utime = 1000 + seq;
  f.seq = seq;
  f.width = 48;
  f.height = 32;
  f.pixel_format = F::FORMAT_GRAY8;
  f.geometry = geometry;
  f.depth_mm = 60;
  if (geometry == F::GEOMETRY_LINEAR) {
    f.width_mm = 40;
  } else {
    f.fan_angle_deg = 60;
    f.radius_of_curvature_mm = 40;
  }
  f.gain_db = -3;
  f.frequency_mhz = 5;
  f.origin_mm[1] = -29.5;
  f.beam[1] = 1;
  f.lateral[2] = 1;
  f.probe_force_n[1] = -1.5;
  f.sim_time_s = 0.5 + seq / 30.0;
  f.num_bytes = f.width * f.height;
  for (int i = 0; i < f.num_bytes; ++i) f.data.push_back(static_cast<uint8_t>(i * 7 + seq));
  return f;
}

pcisim_lcm::xray_frame_t xray_frame(int64_t seq) {
  pcisim_lcm::xray_frame_t f{};
  f.seq = seq;
  f.width = f.height = 8;
  f.pixel_format = pcisim_lcm::xray_frame_t::FORMAT_GRAY16;
  f.pixel_mm = 0.4;
  f.detector_u[0] = f.detector_v[2] = 1;
  f.cine_run = -1;
  f.num_bytes = 128;
  f.data.assign(128, 9);
  return f;
}

std::vector<uint8_t> read_png8(const fs::path& path, int* w, int* h, int* depth, int* colour) {
  FILE* fp = fopen(path.c_str(), "rb");
  EXPECT_NE(fp, nullptr) << path;
  if (!fp) return {};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, fp);
  png_read_info(png, info);
  *w = static_cast<int>(png_get_image_width(png, info));
  *h = static_cast<int>(png_get_image_height(png, info));
  *depth = png_get_bit_depth(png, info);
  *colour = png_get_color_type(png, info);
  std::vector<uint8_t> out(static_cast<size_t>(*w) * *h);
  for (int r = 0; r < *h; ++r) png_read_row(png, out.data() + static_cast<size_t>(r) * *w, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  fclose(fp);
  return out;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::path(::testing::TempDir()) / name;
  fs::remove_all(d);
  return d;
}

template <class M>
void publish(lcm::LCM& lcm, const char* channel, const M& m) {
  lcm.publish(channel, &m);
}

void drain(lcm::LCM& lcm) {
  while (lcm.handleTimeout(10) > 0) {}
}

TEST(UltrasoundCapture, FramesOverLcmLandAsGreyPngsWithTheirGeometryBesideXray) {
  const fs::path dir = fresh_dir("pcisim_capture_us");
  FrameWriter writer(dir.string());
  // pedal gating on and no pedal down: it holds back X-ray only, no pedal drives the probe
  CaptureSink sink(writer, 0, /*only_while_pedal=*/true);
  lcm::LCM images("memq://");
  images.subscribe(protocol::kXrayChannel, &CaptureSink::on_frame, &sink);
  images.subscribe(protocol::kUltrasoundChannel, &CaptureSink::on_ultrasound, &sink);

  const F linear = us_frame(12);
  const F curved = us_frame(13, F::GEOMETRY_CURVILINEAR);
  publish(images, protocol::kUltrasoundChannel, linear);
  publish(images, protocol::kXrayChannel, xray_frame(12));
  publish(images, protocol::kUltrasoundChannel, curved);
  drain(images);
  EXPECT_EQ(writer.written_ultrasound(), 2);
  EXPECT_EQ(writer.written_xray(), 0);
  EXPECT_EQ(sink.skipped(), 1) << "the X-ray frame with the pedal up";
  EXPECT_EQ(sink.bad_ultrasound(), 0);
  EXPECT_TRUE(sink.error().empty()) << sink.error();

  for (const F* f : {&linear, &curved}) {
    const fs::path png = dir / "ultrasound" / fmt::format("frame_{:06d}.png", f->seq);
    int w = 0, h = 0, depth = 0, colour = -1;
    const auto pixels = read_png8(png, &w, &h, &depth, &colour);
    EXPECT_EQ(w, 48);
    EXPECT_EQ(h, 32);
    EXPECT_EQ(depth, 8);
    EXPECT_EQ(colour, PNG_COLOR_TYPE_GRAY);
    EXPECT_EQ(pixels, f->data) << "pixels equal the message's bytes, row 0 at the transducer first";

    const auto j = read_json(dir / "ultrasound" / fmt::format("frame_{:06d}.json", f->seq));
    EXPECT_EQ(j["modality"], "ultrasound");
    EXPECT_EQ(j["frame"], f->seq);
    EXPECT_EQ(j["utime"], f->utime);
    EXPECT_DOUBLE_EQ(j["sim_time_s"].get<double>(), f->sim_time_s);
    EXPECT_DOUBLE_EQ(j["depth_mm"].get<double>(), 60.0);
    EXPECT_DOUBLE_EQ(j["gain_db"].get<double>(), -3.0);
    EXPECT_DOUBLE_EQ(j["frequency_mhz"].get<double>(), 5.0);
    EXPECT_DOUBLE_EQ(j["origin_mm"][1].get<double>(), -29.5);
    EXPECT_DOUBLE_EQ(j["beam"][1].get<double>(), 1.0);
    EXPECT_DOUBLE_EQ(j["lateral"][2].get<double>(), 1.0);
    EXPECT_DOUBLE_EQ(j["probe_force_n"][1].get<double>(), -1.5);
    EXPECT_EQ(j["image"]["width"], 48);
    EXPECT_EQ(j["image"]["height"], 32);
  }
  const auto lj = read_json(dir / "ultrasound" / "frame_000012.json");
  EXPECT_EQ(lj["geometry"], "linear");
  EXPECT_DOUBLE_EQ(lj["width_mm"].get<double>(), 40.0);
  EXPECT_FALSE(lj.contains("fan_angle_deg")) << "only the frame's own geometry";
  // linear: the first pixel's centre half a pixel in from the array's -lateral end
  EXPECT_DOUBLE_EQ(lj["image"]["x0_mm"].get<double>(), -20.0);
  EXPECT_DOUBLE_EQ(lj["image"]["y0_mm"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(lj["image"]["pixel_mm"][0].get<double>(), 40.0 / 48);
  EXPECT_DOUBLE_EQ(lj["image"]["pixel_mm"][1].get<double>(), 60.0 / 32);

  const auto cj = read_json(dir / "ultrasound" / "frame_000013.json");
  EXPECT_EQ(cj["geometry"], "curvilinear");
  EXPECT_DOUBLE_EQ(cj["fan_angle_deg"].get<double>(), 60.0);
  EXPECT_DOUBLE_EQ(cj["radius_of_curvature_mm"].get<double>(), 40.0);
  EXPECT_FALSE(cj.contains("width_mm"));
  // the fan's bounding rectangle: (Rc + depth) sin 30 deg either side, from Rc (cos 30 deg - 1) above the face
  EXPECT_NEAR(cj["image"]["x0_mm"].get<double>(), -50.0, 1e-9);
  EXPECT_NEAR(cj["image"]["y0_mm"].get<double>(), 40.0 * (std::cos(std::numbers::pi / 6) - 1.0), 1e-9);
  EXPECT_NEAR(cj["image"]["pixel_mm"][0].get<double>(), 100.0 / 48, 1e-12);
}

TEST(UltrasoundCapture, ABadFrameIsCountedAndNotWritten) {
  const fs::path dir = fresh_dir("pcisim_capture_us_bad");
  FrameWriter writer(dir.string());
  CaptureSink sink(writer, 0, false);
  lcm::LCM images("memq://");
  images.subscribe(protocol::kUltrasoundChannel, &CaptureSink::on_ultrasound, &sink);

  F short_frame = us_frame(1);  // one byte short of width x height
  short_frame.num_bytes -= 1;
  short_frame.data.pop_back();
  F along_beam = us_frame(2);  // no image plane
  along_beam.lateral[2] = 0;
  along_beam.lateral[1] = 1;
  F nan_origin = us_frame(3);
  nan_origin.origin_mm[0] = std::nan("");
  for (const F* f : {&short_frame, &along_beam, &nan_origin}) publish(images, protocol::kUltrasoundChannel, *f);
  const uint8_t garbage[] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  images.publish(protocol::kUltrasoundChannel, garbage, sizeof garbage);
  // an X-ray frame on the ultrasound channel: the wrong fingerprint
  publish(images, protocol::kUltrasoundChannel, xray_frame(4));
  drain(images);
  EXPECT_EQ(sink.bad_ultrasound(), 5);
  EXPECT_EQ(sink.bad(), 0) << "X-ray's count is X-ray's";
  EXPECT_EQ(writer.written(), 0);
  EXPECT_FALSE(fs::exists(dir / "ultrasound")) << "nothing written for a bad frame";

  publish(images, protocol::kUltrasoundChannel, us_frame(5));
  drain(images);
  EXPECT_EQ(writer.written_ultrasound(), 1) << "a good frame after the bad ones";
  EXPECT_TRUE(fs::exists(dir / "ultrasound" / "frame_000005.png"));
  EXPECT_TRUE(sink.error().empty()) << sink.error();
}

TEST(UltrasoundCapture, WriterRefusesAFrameThatIsNotEightBitWidthByHeight) {
  const fs::path dir = fresh_dir("pcisim_capture_us_format");
  FrameWriter writer(dir.string());
  F f = us_frame(3);
  f.data.pop_back();
  EXPECT_THROW(writer.write(f), std::runtime_error);
  f = us_frame(3);
  f.pixel_format = 2;
  EXPECT_THROW(writer.write(f), std::runtime_error);
  EXPECT_EQ(writer.written(), 0);
}

// a scene reload numbers the probe's frames from 0 again: like X-ray, never over an older frame
TEST(UltrasoundCapture, FramesNumberedAgainAfterAReloadGoToANewFolder) {
  const fs::path dir = fresh_dir("pcisim_capture_us_restart");
  FrameWriter writer(dir.string());
  writer.write(us_frame(0));
  writer.write(us_frame(1));
  EXPECT_EQ(writer.write(us_frame(0)), (dir / "restart_01" / "ultrasound" / "frame_000000.png").string());
  EXPECT_TRUE(fs::exists(dir / "ultrasound" / "frame_000001.png"));
  EXPECT_EQ(writer.written_ultrasound(), 3);
  EXPECT_EQ(writer.written(), 3);
}

// --frames counts both kinds
TEST(UltrasoundCapture, TheFrameLimitCountsUltrasoundToo) {
  const fs::path dir = fresh_dir("pcisim_capture_us_limit");
  FrameWriter writer(dir.string());
  CaptureSink sink(writer, 3, false);
  lcm::LCM images("memq://");
  images.subscribe(protocol::kXrayChannel, &CaptureSink::on_frame, &sink);
  images.subscribe(protocol::kUltrasoundChannel, &CaptureSink::on_ultrasound, &sink);
  publish(images, protocol::kXrayChannel, xray_frame(0));
  for (int64_t i = 0; i < 4; ++i) publish(images, protocol::kUltrasoundChannel, us_frame(i));
  drain(images);
  EXPECT_TRUE(sink.done());
  EXPECT_EQ(writer.written_xray(), 1);
  EXPECT_EQ(writer.written_ultrasound(), 2);
}

}  // namespace
}  // namespace pcisim::clients
