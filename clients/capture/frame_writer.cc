#include "clients/capture/frame_writer.h"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <unistd.h>

#include "png/png_gray.h"
#include "protocol/us_frame_geometry.h"

namespace pcisim::clients {
namespace fs = std::filesystem;

FrameWriter::FrameWriter(const std::string& out_dir) : out_dir_(out_dir) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) throw std::runtime_error(fmt::format("{}: cannot create the output folder: {}", out_dir, ec.message()));
  if (access(out_dir.c_str(), W_OK) != 0)
    throw std::runtime_error(fmt::format("{}: cannot write into the output folder: {}", out_dir, std::strerror(errno)));
}

nlohmann::json FrameWriter::sidecar(const pcisim_lcm::xray_frame_t& f) {
  auto v3 = [](const double* p) { return nlohmann::json::array({p[0], p[1], p[2]}); };
  nlohmann::json wire_mm = nlohmann::json::array(), wire_px = nlohmann::json::array();
  for (int i = 0; i < f.num_wire_points; ++i) {
    wire_mm.push_back({f.wire_mm[i][0], f.wire_mm[i][1], f.wire_mm[i][2]});
    wire_px.push_back({f.wire_px[i][0], f.wire_px[i][1]});
  }
  return {
      {"modality", "xray"},
      {"frame", f.seq},
      {"sim_time_s", f.sim_time_s},
      {"utime", f.utime},
      {"cine", f.cine != 0},
      {"cine_run", f.cine_run},
      {"c_arm",
       {{"primary_deg", f.primary_angle_deg},
        {"secondary_deg", f.secondary_angle_deg},
        {"source_to_image_mm", f.source_to_image_mm},
        {"source_to_axis_mm", f.source_to_axis_mm}}},
      {"detector",
       {{"width", f.width},
        {"height", f.height},
        {"pixel_mm", f.pixel_mm},
        {"source_mm", v3(f.source_mm)},
        {"center_mm", v3(f.detector_center_mm)},
        {"u", v3(f.detector_u)},
        {"v", v3(f.detector_v)},
        {"pixel_center",
         "center_mm + (c - (width-1)/2) pixel_mm u + (r - (height-1)/2) pixel_mm v; rays from source_mm"}}},
      {"labels",
       {{"wire_mm", wire_mm},
        {"wire_px", wire_px},
        {"tip_px", f.num_wire_points > 0 ? wire_px.back() : nlohmann::json(nullptr)},
        {"contrast_branches", f.contrast_branches}}},
  };
}

nlohmann::json FrameWriter::sidecar(const pcisim_lcm::us_frame_t& f) {
  using F = pcisim_lcm::us_frame_t;
  auto v3 = [](const double* p) { return nlohmann::json::array({p[0], p[1], p[2]}); };
  const bool linear = f.geometry == F::GEOMETRY_LINEAR;
  const protocol::UsImagePlane plane = protocol::us_image_plane(f);
  nlohmann::json j = {
      {"modality", "ultrasound"},
      {"frame", f.seq},
      {"sim_time_s", f.sim_time_s},
      {"utime", f.utime},
      {"geometry", linear ? "linear" : "curvilinear"},
      {"depth_mm", f.depth_mm},
      {"gain_db", f.gain_db},
      {"frequency_mhz", f.frequency_mhz},
      {"origin_mm", v3(f.origin_mm)},
      {"beam", v3(f.beam)},
      {"lateral", v3(f.lateral)},
      {"probe_force_n", v3(f.probe_force_n)},
      {"image",
       {{"width", f.width},
        {"height", f.height},
        {"x0_mm", plane.x0_mm},
        {"y0_mm", plane.y0_mm},
        {"pixel_mm", {plane.pixel_x_mm, plane.pixel_y_mm}},
        {"pixel_center",
         "origin_mm + (x0_mm + (c + 0.5) pixel_mm[0]) lateral + (y0_mm + (r + 0.5) pixel_mm[1]) beam"}}},
  };
  // only the fields of the frame's own geometry: the other's are not set by the server
  if (linear) {
    j["width_mm"] = f.width_mm;
  } else {
    j["fan_angle_deg"] = f.fan_angle_deg;
    j["radius_of_curvature_mm"] = f.radius_of_curvature_mm;
    j["image"]["outside_fan"] = "black (0)";
  }
  return j;
}

std::string FrameWriter::write(const pcisim_lcm::xray_frame_t& f) {
  if (f.pixel_format != pcisim_lcm::xray_frame_t::FORMAT_GRAY16 ||
      static_cast<int64_t>(f.data.size()) != int64_t{f.width} * f.height * 2)
    throw std::runtime_error(fmt::format("frame {}: not a 16-bit frame of {}x{} pixels", f.seq, f.width, f.height));
  const std::string leaf = f.cine ? fmt::format("cine_{:03d}", f.cine_run) : std::string("fluoro");
  const std::string png = write_files(leaf, f.seq, sidecar(f), [&](const std::string& path) {
    png::write_png_gray16(path, f.width, f.height, reinterpret_cast<const uint16_t*>(f.data.data()));
  });
  ++written_xray_;
  return png;
}

std::string FrameWriter::write(const pcisim_lcm::us_frame_t& f) {
  if (f.pixel_format != pcisim_lcm::us_frame_t::FORMAT_GRAY8 || f.width <= 0 || f.height <= 0 ||
      static_cast<int64_t>(f.data.size()) != int64_t{f.width} * f.height)
    throw std::runtime_error(
        fmt::format("ultrasound frame {}: not an 8-bit frame of {}x{} pixels", f.seq, f.width, f.height));
  const std::string png = write_files("ultrasound", f.seq, sidecar(f), [&](const std::string& path) {
    png::write_png_gray8(path, f.width, f.height, f.data.data());
  });
  ++written_ultrasound_;
  return png;
}

std::string FrameWriter::write_files(const std::string& leaf, int64_t seq, const nlohmann::json& sidecar,
                                     const std::function<void(const std::string&)>& write_png) {
  // a server that restarts its pipeline (a scene reload) numbers its frames from 0 again: a frame
  // whose file exists starts a new restart_NN/ folder, so no frame is ever written over
  auto folder = [&] {
    return restart_ == 0 ? fs::path(out_dir_) / leaf
                         : fs::path(out_dir_) / fmt::format("restart_{:02d}", restart_) / leaf;
  };
  std::error_code ec;
  while (fs::exists(folder() / fmt::format("frame_{:06d}.png", seq), ec)) ++restart_;
  const fs::path dir = folder();
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(fmt::format("{}: cannot create: {}", dir.string(), ec.message()));
  const fs::path png = dir / fmt::format("frame_{:06d}.png", seq);
  const fs::path json = dir / fmt::format("frame_{:06d}.json", seq);
  const fs::path png_tmp = dir / fmt::format(".frame_{:06d}.png.tmp", seq);
  const fs::path json_tmp = dir / fmt::format(".frame_{:06d}.json.tmp", seq);
  try {
    write_png(png_tmp.string());
    std::ofstream out(json_tmp);
    out << sidecar.dump(1) << "\n";
    out.flush();
    if (!out)
      throw std::runtime_error(
          fmt::format("{}: writing the sidecar failed: {}", json_tmp.string(), std::strerror(errno)));
    out.close();
    // the sidecar lands first: a PNG in place always has its labels
    fs::rename(json_tmp, json);
    fs::rename(png_tmp, png);
  } catch (...) {
    fs::remove(png_tmp, ec);
    fs::remove(json_tmp, ec);
    throw;
  }
  return png.string();
}

}  // namespace pcisim::clients
