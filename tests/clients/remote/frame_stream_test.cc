// Frames reach every page, newest first: a page that reads slowly gets fewer frames, never a
// backlog, and never slows the others. What the gateway holds for pages stays bounded.
#include <gtest/gtest.h>
#include <png.h>
#include <turbojpeg.h>

#include <cmath>
#include <numbers>
#include <random>

#include "clients/remote/frame_encoder.h"
#include "clients/remote/latest_frame_slot.h"
#include "remote_test_support.h"

namespace pcisim::remote::test {
namespace {

// decodes a JPEG to 8-bit grey
std::vector<uint8_t> decode_jpeg(const std::string& jpeg, int& w, int& h) {
  tjhandle tj = tjInitDecompress();
  int sub = 0, cs = 0;
  auto* src = reinterpret_cast<const unsigned char*>(jpeg.data());
  std::vector<uint8_t> out;
  if (tjDecompressHeader3(tj, src, jpeg.size(), &w, &h, &sub, &cs) == 0) {
    out.resize(static_cast<size_t>(w) * h);
    if (tjDecompress2(tj, src, jpeg.size(), out.data(), w, 0, h, TJPF_GRAY, 0) != 0) out.clear();
  }
  tjDestroy(tj);
  return out;
}

// decodes a PNG held in memory; empty unless it is 8-bit grey
std::vector<uint8_t> decode_png8(const std::string& bytes, int& w, int& h) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  std::vector<uint8_t> out;
  if (!png_image_begin_read_from_memory(&image, bytes.data(), bytes.size())) return out;
  const bool gray8 = image.format == PNG_FORMAT_GRAY;  // the file's own format, before any conversion
  w = static_cast<int>(image.width);
  h = static_cast<int>(image.height);
  out.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, out.data(), 0, nullptr) || !gray8) out.clear();
  png_image_free(&image);
  return out;
}

// a curvilinear B-mode frame: 60 deg, Rc 40 mm, 60 mm deep; speckle-like bytes
pcisim_lcm::us_frame_t make_us_frame(int64_t seq, int width = 96, int height = 64) {
  using U = pcisim_lcm::us_frame_t;
  U f{};
  f.seq = seq;
  f.utime = 500 + seq;
  f.width = width;
  f.height = height;
  f.pixel_format = U::FORMAT_GRAY8;
  f.geometry = U::GEOMETRY_CURVILINEAR;
  f.depth_mm = 60;
  f.fan_angle_deg = 60;
  f.radius_of_curvature_mm = 40;
  f.gain_db = 6;
  f.frequency_mhz = 3.5;
  f.beam[1] = 1;
  f.lateral[2] = 1;
  f.probe_force_n[0] = 3;
  f.probe_force_n[1] = -4;
  f.sim_time_s = 2.5;
  f.num_bytes = width * height;
  std::mt19937 rng(static_cast<unsigned>(seq));
  for (int i = 0; i < f.num_bytes; ++i) f.data.push_back(static_cast<uint8_t>(rng()));
  return f;
}

TEST(RemoteFrames, WindowMaps16BitsTo8) {
  EXPECT_EQ(window_to_8bit(0, 0, 65535), 0);
  EXPECT_EQ(window_to_8bit(65535, 0, 65535), 255);
  EXPECT_EQ(window_to_8bit(32768, 0, 65535), 128);
  EXPECT_EQ(window_to_8bit(1000, 2000, 3000), 0);
  EXPECT_EQ(window_to_8bit(2500, 2000, 3000), 128);
  EXPECT_EQ(window_to_8bit(5000, 2000, 3000), 255);
}

TEST(RemoteFrames, EncodesJpegAndPngThatDecodeToTheWindowedImage) {
  auto frame = make_frame(7, 64, 1000);
  EncoderOptions jo;
  jo.jpeg_quality = 100;
  FrameEncoder jpeg(jo);
  const auto e = jpeg.encode(frame);
  WsMessage m{true, e->message};
  EXPECT_EQ(m.frame_header()["seq"], 7);
  EXPECT_EQ(m.frame_header()["mime"], "image/jpeg");
  EXPECT_EQ(m.frame_header()["width"], 64);
  int w = 0, h = 0;
  const auto px = decode_jpeg(m.image(), w, h);
  ASSERT_EQ(px.size(), 64u * 64u);
  double err = 0;
  for (int i = 0; i < 64 * 64; ++i) {
    const uint16_t v = static_cast<uint16_t>(frame.data[2 * i] | frame.data[2 * i + 1] << 8);
    err = std::max(err, std::abs(px[i] - static_cast<double>(v >> 8)));
  }
  EXPECT_LE(err, 6) << "quality 100 JPEG stays within a few grey levels of the window";

  EncoderOptions po;
  po.format = ImageFormat::kPng;
  FrameEncoder png(po);
  const WsMessage pm{true, png.encode(frame)->message};
  EXPECT_EQ(pm.frame_header()["mime"], "image/png");
  EXPECT_EQ(pm.image().substr(1, 3), "PNG");

  auto bad = frame;
  bad.data.resize(10);
  EXPECT_THROW(jpeg.encode(bad), std::runtime_error);
}

// an ultrasound frame is shown as the renderer made it (8 bits, no window), tagged with its kind
// and its geometry; its size in mm lets the page keep its aspect
TEST(RemoteFrames, UltrasoundFrameKeepsItsGreyLevelsAndCarriesItsGeometry) {
  const auto frame = make_us_frame(4);
  EncoderOptions po;
  po.format = ImageFormat::kPng;
  po.window_lo = 1000;  // an X-ray window must not touch ultrasound grey levels
  po.window_hi = 2000;
  FrameEncoder png(po);
  const WsMessage m{true, png.encode(frame)->message};
  const auto h = m.frame_header();
  EXPECT_EQ(h["kind"], "ultrasound");
  EXPECT_EQ(h["seq"], 4);
  EXPECT_EQ(h["width"], 96);
  EXPECT_EQ(h["height"], 64);
  EXPECT_EQ(h["geometry"], "curvilinear");
  EXPECT_DOUBLE_EQ(h["depth_mm"].get<double>(), 60.0);
  EXPECT_DOUBLE_EQ(h["fan_angle_deg"].get<double>(), 60.0);
  EXPECT_DOUBLE_EQ(h["radius_of_curvature_mm"].get<double>(), 40.0);
  EXPECT_DOUBLE_EQ(h["gain_db"].get<double>(), 6.0);
  EXPECT_DOUBLE_EQ(h["frequency_mhz"].get<double>(), 3.5);
  EXPECT_DOUBLE_EQ(h["probe_force_n"][1].get<double>(), -4.0);
  // the fan's bounding box: 2 (Rc + depth) sin 30 deg wide, depth - Rc (cos 30 deg - 1) high
  EXPECT_NEAR(h["image_mm"][0].get<double>(), 100.0, 1e-9);
  EXPECT_NEAR(h["image_mm"][1].get<double>(), 60.0 - 40.0 * (std::cos(std::numbers::pi / 6) - 1.0), 1e-9);
  EXPECT_FALSE(h.contains("primary_deg")) << "no C-arm in an ultrasound frame";
  int w = 0, hh = 0;
  EXPECT_EQ(decode_png8(m.image(), w, hh), frame.data) << "PNG: the message's bytes exactly";

  FrameEncoder jpeg({});
  const WsMessage jm{true, jpeg.encode(frame)->message};
  EXPECT_EQ(jm.frame_header()["mime"], "image/jpeg");
  EXPECT_EQ(decode_jpeg(jm.image(), w, hh).size(), 96u * 64u);
  const WsMessage xm{true, jpeg.encode(make_frame(1, 64))->message};
  EXPECT_EQ(xm.frame_header()["kind"], "xray");

  auto bad = frame;
  bad.data.pop_back();
  EXPECT_THROW(jpeg.encode(bad), std::runtime_error);
  bad = frame;
  bad.pixel_format = 3;
  EXPECT_THROW(jpeg.encode(bad), std::runtime_error);
}

// one slot per modality: an ultrasound frame never replaces a waiting X-ray frame, nor the reverse
TEST(RemoteFrames, TheNewestFrameOfEachModalityWaits) {
  LatestFrameSlot slot;
  pcisim_lcm::xray_frame_t x = make_frame(1, 8), x_out;
  pcisim_lcm::us_frame_t u = make_us_frame(7, 8, 8), u_out;
  slot.put(x);
  slot.put(u);
  x = make_frame(2, 8);
  slot.put(x);
  EXPECT_EQ(slot.take(x_out, u_out, 0), LatestFrameSlot::kXray | LatestFrameSlot::kUltrasound);
  EXPECT_EQ(x_out.seq, 2) << "the newer X-ray frame";
  EXPECT_EQ(u_out.seq, 7);
  EXPECT_EQ(slot.replaced(), 1);
  EXPECT_EQ(slot.take(x_out, u_out, 0), LatestFrameSlot::kNone);
  u = make_us_frame(8, 8, 8);
  slot.put(u);
  EXPECT_EQ(slot.take(x_out, u_out, 0), LatestFrameSlot::kUltrasound);
  EXPECT_EQ(u_out.seq, 8);
  EXPECT_EQ(x_out.seq, 2) << "untouched";
}

// the soft-tissue scene's frames on PCISIM_ULTRASOUND (image bus) reach the page, tagged; a bad one is
// counted as ultrasound's and never shown
TEST(RemoteFrames, UltrasoundFramesOverLcmReachThePage) {
  TestGateway g;
  WsClient c;
  ASSERT_EQ(c.connect(g.port(), ws_target(kObserverToken)), 101);
  ASSERT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 1; }));
  auto along_beam = make_us_frame(100);  // lateral along the beam: no image plane
  along_beam.lateral[1] = 1;
  along_beam.lateral[2] = 0;
  g.images.publish(protocol::kUltrasoundChannel, &along_beam);
  for (int i = 0; i < 5; ++i) {
    auto f = make_us_frame(i);
    g.images.publish(protocol::kUltrasoundChannel, &f);
    std::this_thread::sleep_for(50ms);
  }
  int n = 0;
  int64_t last = -1;
  while (auto m = c.next_frame(1000ms)) {
    const auto h = m->frame_header();
    EXPECT_EQ(h["kind"], "ultrasound");
    EXPECT_NE(h["seq"], 100) << "the bad frame was shown";
    last = h["seq"];
    ++n;
    if (last == 4) break;
  }
  EXPECT_EQ(last, 4);
  EXPECT_GE(n, 3) << "at 20 fps below the cap, most arrive";
  const auto k = g.gateway->counters();
  EXPECT_EQ(k.ultrasound_received, 5);
  EXPECT_EQ(k.ultrasound_bad, 1);
  EXPECT_EQ(k.frames_received, 0) << "X-ray's counters are X-ray's";
  EXPECT_EQ(k.frames_bad, 0);

  // the scene changes to X-ray: the same page gets X-ray frames next
  auto x = make_frame(0, 64);
  g.images.publish(protocol::kXrayChannel, &x);
  auto m = c.next_frame(2000ms);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->frame_header()["kind"], "xray");
}

TEST(RemoteFrames, EveryPageGetsTheNewestFrames) {
  TestGateway g;
  WsClient a, b;
  ASSERT_EQ(a.connect(g.port(), ws_target(kObserverToken)), 101);
  ASSERT_EQ(b.connect(g.port(), ws_target(kControllerToken)), 101);
  ASSERT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 2; }));
  for (int i = 0; i < 10; ++i) {
    auto f = make_frame(i, 128, static_cast<uint16_t>(i * 3000));
    g.images.publish(protocol::kXrayChannel, &f);
    std::this_thread::sleep_for(40ms);
  }
  for (WsClient* c : {&a, &b}) {
    int64_t last = -1;
    int n = 0;
    std::string first_image, last_image;
    while (auto m = c->next_frame(1000ms)) {
      const int64_t seq = m->frame_header()["seq"];
      EXPECT_GT(seq, last) << "frames never go backwards";
      last = seq;
      if (n++ == 0) first_image = m->image();
      last_image = m->image();
      if (seq == 9) break;
    }
    EXPECT_EQ(last, 9);
    EXPECT_GE(n, 5) << "at 25 fps below the 30 fps cap, most arrive (a stalled machine may merge a few)";
    EXPECT_NE(first_image, last_image) << "pixels change between frames";
  }
}

TEST(RemoteFrames, SlowPageGetsFewerFramesAndMemoryStaysBounded) {
  GatewayOptions o;
  o.hub.max_fps = 60;
  o.hub.socket_send_buffer = 64 * 1024;  // the kernel holds only a few frames, so the gateway's own dropping shows
  TestGateway g(o);
  WsClient fast, slow;
  ASSERT_EQ(fast.connect(g.port(), ws_target(kObserverToken)), 101);
  // a page that stops reading: a tiny receive buffer, nothing read
  ASSERT_EQ(slow.connect(g.port(), ws_target(kObserverToken), false, 4096), 101);
  ASSERT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 2; }));

  // 150 noisy 256x256 frames at ~75 fps: far more than the slow page's socket can hold
  size_t largest = 0;
  int64_t max_pending = 0;
  int fast_frames = 0;
  int64_t fast_last = -1;
  std::thread reader([&] {
    while (auto m = fast.next_frame(1500ms)) {
      ++fast_frames;
      fast_last = m->frame_header()["seq"];
      if (fast_last == 149) break;
    }
  });
  for (int i = 0; i < 150; ++i) {
    auto f = make_frame(i, 256, 0, 99);
    g.images.publish(protocol::kXrayChannel, &f);
    std::this_thread::sleep_for(13ms);
    max_pending = std::max(max_pending, g.gateway->hub_stats().bytes_pending);
  }
  reader.join();
  // the encoded size of one frame, for the bound
  FrameEncoder enc({});
  for (int i = 0; i < 5; ++i) largest = std::max(largest, enc.encode(make_frame(i, 256, 0, 99))->message.size());

  const HubStats s = g.gateway->hub_stats();
  EXPECT_GT(s.frames_dropped, 100) << "the stalled page's stale frames were dropped, not queued";
  // per page at most one frame waiting and one in flight
  EXPECT_LE(max_pending, static_cast<int64_t>(4 * largest + 4096)) << "largest frame " << largest;
  EXPECT_LE(s.bytes_pending, static_cast<int64_t>(2 * largest + 4096));
  // the fast page was not held back by the slow one
  EXPECT_EQ(fast_last, 149);
  EXPECT_GE(fast_frames, 100);

  // once the slow page reads again it gets the newest frame after at most a couple of stale ones
  slow.start_reading();
  int stale = 0;
  bool got_newest = false;
  while (auto m = slow.next_frame(2000ms)) {
    if (m->frame_header()["seq"] == 149) {
      got_newest = true;
      break;
    }
    ++stale;
  }
  EXPECT_TRUE(got_newest);
  // what the kernel's socket buffers held (a few frames) arrives first; the ~140 dropped never do
  EXPECT_LE(stale, 12) << "frame of " << largest << " bytes";
}

// publishes `count` small frames at 20 fps and counts what the page receives; *seconds gets how
// long that took, the page's last frames included
int frames_received_at_20_fps(TestGateway& g, WsClient& c, int count, double* seconds) {
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < count; ++i) {
    auto f = make_frame(i, 64);
    g.images.publish(protocol::kXrayChannel, &f);
    std::this_thread::sleep_for(50ms);
  }
  int n = 0;
  while (c.next_frame(300ms)) ++n;
  *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return n;
}

TEST(RemoteFrames, PageMayAskForFewerFrames) {
  TestGateway g;
  WsClient c;
  ASSERT_EQ(c.connect(g.port(), ws_target(kObserverToken) + "&fps=5"), 101);
  ASSERT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 1; }));
  double s = 0;
  const int n = frames_received_at_20_fps(g, c, 40, &s);  // 2 s
  EXPECT_GE(n, 4) << "frames still flow at the asked rate";
  EXPECT_LE(n, static_cast<int>(5 * s) + 2) << n << " frames in " << s << " s";
  c.send({{"type", "set_fps"}, {"fps", 1000}});
  auto err = c.next_of("error");
  ASSERT_TRUE(err);
  EXPECT_EQ((*err)["code"], "out_of_range");
}

TEST(RemoteFrames, UnreadableFrameRateRequestGetsTheCap) {
  GatewayOptions o;
  o.hub.max_fps = 5;
  TestGateway g(o);
  for (const char* asked : {"nan", "inf", "-inf", "fast"}) {
    WsClient c;
    ASSERT_EQ(c.connect(g.port(), ws_target(kObserverToken) + "&fps=" + asked), 101) << asked;
    ASSERT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 1; })) << asked;
    double s = 0;
    const int n = frames_received_at_20_fps(g, c, 20, &s);  // 1 s
    EXPECT_GE(n, 3) << asked;
    EXPECT_LE(n, static_cast<int>(5 * s) + 2) << asked << ": " << n << " frames in " << s << " s, over the 5 fps cap";
    c.close_hard();
    ASSERT_TRUE(eventually([&] { return g.gateway->hub_stats().clients == 0; })) << asked;
  }
}

TEST(RemoteFrames, BadFramesAreCountedAndDropped) {
  TestGateway g;
  auto f = make_frame(1, 64);
  f.num_bytes = 10;  // sizes disagree: the checked decode refuses it
  f.data.resize(10);
  g.images.publish(protocol::kXrayChannel, &f);
  auto weird = make_frame(2, 64);
  weird.pixel_format = pcisim_lcm::xray_frame_t::FORMAT_PNG;
  g.images.publish(protocol::kXrayChannel, &weird);
  EXPECT_TRUE(eventually([&] {
    const auto c = g.gateway->counters();
    return c.frames_bad + c.frames_received == 2 && c.encode_errors + c.frames_bad == 2;
  }));
  EXPECT_EQ(g.gateway->counters().frames_encoded, 0);
}

}  // namespace
}  // namespace pcisim::remote::test
