#include "clients/capture/frame_writer.h"

#include <gtest/gtest.h>
#include <png.h>
#include <sys/resource.h>

#include <csignal>
#include <filesystem>
#include <fstream>

namespace pcisim::clients {
namespace {

namespace fs = std::filesystem;

pcisim_lcm::xray_frame_t make_frame(int64_t seq, int w = 64, int h = 48, bool cine = false) {
  pcisim_lcm::xray_frame_t f{};
  f.seq = seq;
  f.width = w;
  f.height = h;
  f.pixel_format = pcisim_lcm::xray_frame_t::FORMAT_GRAY16;
  f.pixel_mm = 0.4;
  f.source_mm[1] = 750;
  f.detector_center_mm[1] = -350;
  f.detector_u[0] = 1;
  f.detector_v[2] = -1;
  f.cine = cine ? 1 : 0;
  f.cine_run = cine ? 2 : -1;
  f.num_wire_points = 2;
  f.wire_mm = {{0, 0, 0}, {1, 2, 3}};
  f.wire_px = {{31.5f, 23.5f}, {34.2f, 31.0f}};
  f.num_contrast_branches = 1;
  f.contrast_branches = {"LAD"};
  f.num_bytes = w * h * 2;
  f.data.resize(f.num_bytes);
  auto* px = reinterpret_cast<uint16_t*>(f.data.data());
  for (int i = 0; i < w * h; ++i) px[i] = static_cast<uint16_t>(i * 37 + seq);
  return f;
}

std::vector<uint16_t> read_png16(const std::string& path, int* w, int* h) {
  FILE* fp = fopen(path.c_str(), "rb");
  EXPECT_NE(fp, nullptr);
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, fp);
  png_read_info(png, info);
  *w = png_get_image_width(png, info);
  *h = png_get_image_height(png, info);
  EXPECT_EQ(png_get_bit_depth(png, info), 16);
  std::vector<uint16_t> out(static_cast<size_t>(*w) * *h);
  std::vector<uint8_t> row(*w * 2);
  for (int r = 0; r < *h; ++r) {
    png_read_row(png, row.data(), nullptr);
    for (int c = 0; c < *w; ++c) out[r * *w + c] = static_cast<uint16_t>(row[2 * c] << 8 | row[2 * c + 1]);
  }
  png_destroy_read_struct(&png, &info, nullptr);
  fclose(fp);
  return out;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / name;
  fs::remove_all(d);
  return d;
}

TEST(FrameWriter, WritesSixteenBitPngsAndSidecarsIntoFluoroAndCineFolders) {
  const fs::path dir = fresh_dir("pcisim_capture_test");
  FrameWriter writer(dir.string());
  const auto frame = make_frame(7);
  const std::string png = writer.write(frame);
  EXPECT_EQ(png, (dir / "fluoro" / "frame_000007.png").string());
  int w = 0, h = 0;
  const auto pixels = read_png16(png, &w, &h);
  ASSERT_EQ(w, 64);
  ASSERT_EQ(h, 48);
  EXPECT_EQ(0, std::memcmp(pixels.data(), frame.data.data(), frame.data.size())) << "pixels survive exactly";
  std::ifstream in(dir / "fluoro" / "frame_000007.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["frame"], 7);
  EXPECT_EQ(j["detector"]["width"], 64);
  EXPECT_DOUBLE_EQ(j["detector"]["source_mm"][1].get<double>(), 750.0);
  EXPECT_EQ(j["labels"]["contrast_branches"][0], "LAD");
  EXPECT_NEAR(j["labels"]["tip_px"][0].get<double>(), 34.2, 1e-5);
  EXPECT_DOUBLE_EQ(j["labels"]["wire_mm"][1][2].get<double>(), 3.0);

  writer.write(make_frame(8, 64, 48, true));
  EXPECT_TRUE(fs::exists(dir / "cine_002" / "frame_000008.png"));
  EXPECT_TRUE(fs::exists(dir / "cine_002" / "frame_000008.json"));
  EXPECT_EQ(writer.written(), 2);
  for (const auto& e : fs::recursive_directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().rfind(".", 0), std::string::npos) << "no temporary file left: " << e.path();
}

// a scene reload restarts the server's frame numbers at 0: the capture once wrote the new
// pipeline's frames over the old ones (the 10-minute soak kept 1464 of 7103 frames)
TEST(FrameWriter, FramesNumberedAgainAfterAReloadGoToANewFolderNeverOverAnOldFrame) {
  const fs::path dir = fresh_dir("pcisim_capture_restart");
  FrameWriter writer(dir.string());
  for (int64_t seq : {0, 1, 2}) writer.write(make_frame(seq));
  const std::string again = writer.write(make_frame(0));
  EXPECT_EQ(again, (dir / "restart_01" / "fluoro" / "frame_000000.png").string());
  writer.write(make_frame(1));
  EXPECT_TRUE(fs::exists(dir / "restart_01" / "fluoro" / "frame_000001.png"));
  writer.write(make_frame(0));
  EXPECT_TRUE(fs::exists(dir / "restart_02" / "fluoro" / "frame_000000.png"));
  EXPECT_TRUE(fs::exists(dir / "fluoro" / "frame_000002.png")) << "the first pipeline's frames stay";
  EXPECT_EQ(writer.written(), 6);
  int pngs = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) pngs += e.path().extension() == ".png";
  EXPECT_EQ(pngs, 6) << "every frame written is on disk";
}

TEST(FrameWriter, AFolderThatCannotBeMadeIsAClearError) {
  try {
    FrameWriter writer("/dev/null/frames");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/null/frames: cannot create the output folder"), std::string::npos)
        << e.what();
  }
}

TEST(FrameWriter, AFullDiskStopsWithAnErrorAndLeavesEarlierFramesIntact) {
  const fs::path dir = fresh_dir("pcisim_capture_full");
  FrameWriter writer(dir.string());
  writer.write(make_frame(1, 32, 32));
  // a file size limit stands in for a full disk: the next, larger frame cannot be written
  std::signal(SIGXFSZ, SIG_IGN);
  rlimit old{};
  getrlimit(RLIMIT_FSIZE, &old);
  rlimit small = old;
  small.rlim_cur = 4096;
  setrlimit(RLIMIT_FSIZE, &small);
  std::string error;
  try {
    writer.write(make_frame(2, 512, 512));
  } catch (const std::runtime_error& e) {
    error = e.what();
  }
  setrlimit(RLIMIT_FSIZE, &old);
  EXPECT_NE(error.find("frame_000002"), std::string::npos) << "the error names the file: " << error;
  EXPECT_FALSE(fs::exists(dir / "fluoro" / "frame_000002.png"));
  EXPECT_FALSE(fs::exists(dir / "fluoro" / ".frame_000002.png.tmp")) << "no half frame left behind";
  int w = 0, h = 0;
  EXPECT_EQ(read_png16((dir / "fluoro" / "frame_000001.png").string(), &w, &h).size(), 32u * 32u);
  EXPECT_TRUE(fs::exists(dir / "fluoro" / "frame_000001.json"));
}

TEST(FrameWriter, RefusesAFrameThatIsNotSixteenBit) {
  const fs::path dir = fresh_dir("pcisim_capture_format");
  FrameWriter writer(dir.string());
  auto f = make_frame(3);
  f.pixel_format = pcisim_lcm::xray_frame_t::FORMAT_GRAY8;
  EXPECT_THROW(writer.write(f), std::runtime_error);
  EXPECT_EQ(writer.written(), 0);
}

}  // namespace
}  // namespace pcisim::clients
