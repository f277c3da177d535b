#include "bench/xray_plastimatch.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "anatomy/volume/volume_io.h"

namespace pcisim::bench {
namespace {

// a PFM image (plastimatch drr -t pfm): "Pf" (one channel), "width height", a scale whose sign
// gives the byte order (negative: little endian), then float rows, taken in the file's order
// (how they meet pcisim's rows: run_plastimatch_drr)
bool read_pfm(const std::string& path, xray::Image* img, std::string* why) {
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    *why = path + ": not written";
    return false;
  }
  std::string magic;
  int w = 0, h = 0;
  double scale = 0;
  f >> magic >> w >> h >> scale;
  f.get();  // the one whitespace character before the data
  if (magic != "Pf" || w <= 0 || h <= 0 || w > 16384 || h > 16384 || scale >= 0) {
    *why = path + ": not a little-endian one-channel PFM";
    return false;
  }
  img->resize(w, h);
  f.read(reinterpret_cast<char*>(img->pixels.data()), static_cast<std::streamsize>(img->pixels.size() * 4));
  if (!f) {
    *why = path + ": shorter than its header says";
    return false;
  }
  return true;
}

// seconds of wall time to run `cmd` through the shell; false when it fails
bool timed_system(const std::string& cmd, double* seconds) {
  const auto t0 = std::chrono::steady_clock::now();
  const int rc = std::system(cmd.c_str());
  *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return rc == 0;
}

std::string quoted(const Eigen::Vector3d& v) {
  return fmt::format("\"{:.9g} {:.9g} {:.9g}\"", v.x(), v.y(), v.z());
}

// a word for the shell: in single quotes, each single quote closed, escaped and opened again
std::string shell_word(const std::string& s) {
  std::string out = "'";
  for (const char ch : s) out += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return out + "'";
}

}  // namespace

std::string find_plastimatch() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const std::string candidate = (dir.empty() ? std::string(".") : dir) + "/plastimatch";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return {};
}

PlastimatchRun run_plastimatch_drr(const std::string& plastimatch, const xray::AttenuationVolume& mu,
                                   const anatomy::Volume& grid, const xray::CArmSpec& c_arm, const xray::CArmPose& pose,
                                   const xray::Image& reference, const std::string& work_dir, int images) {
  PlastimatchRun r;
  if (plastimatch.empty()) {
    r.why = "plastimatch is not installed (Debian package plastimatch)";
    return r;
  }
  std::filesystem::create_directories(work_dir);
  const std::string mha = work_dir + "/mu.mha", log = work_dir + "/plastimatch.log";
  {
    anatomy::Volume v = anatomy::Volume::make(grid.dims, grid.spacing_mm, grid.origin_mm, anatomy::VoxelType::kFloat32);
    v.direction = grid.direction;
    for (int64_t k = 0; k < grid.dims[2]; ++k)
      for (int64_t j = 0; j < grid.dims[1]; ++j)
        for (int64_t i = 0; i < grid.dims[0]; ++i)
          v.hu_f32[v.linear_index(i, j, k)] = mu.mu(static_cast<int>(i), static_cast<int>(j), static_cast<int>(k));
    anatomy::write_metaimage(v, mha);
    r.volume_mib = static_cast<double>(v.voxel_count()) * sizeof(float) / (1024.0 * 1024.0);
  }
  {
    const std::string version_file = work_dir + "/version.txt";
    double s = 0;
    if (timed_system(fmt::format("{} --version > {} 2>&1", shell_word(plastimatch), shell_word(version_file)), &s)) {
      std::ifstream v(version_file);
      std::getline(v, r.version);
    }
  }
  // the geometry: plastimatch's detector normal -n points from the isocentre to the source (pcisim's
  // beam direction d points the other way), --vup from the detector's centre to its top row
  // (pcisim's row 0 lies towards -v). Read in file order, its rows are then pcisim's and its
  // columns run against pcisim's u: mirrored left to right. (Found by trying both signs of each
  // vector and the eight flips and transposes of the image, on the HU volume: correlation 0.9885
  // this way and with vup = v and the rows flipped instead, at most 0.95 every other way.)
  const xray::DetectorGeometry g = xray::c_arm_geometry(c_arm, pose);
  const Eigen::Vector3d d = xray::c_arm_beam_direction(pose.primary_deg, pose.secondary_deg);
  const std::string prefix = work_dir + "/drr_";
  r.command = fmt::format(
      "{} drr -P none -i exact -t pfm -r \"{} {}\" -z \"{:.9g} {:.9g}\" --sad {:.9g} --sid {:.9g} -o {} -n {} "
      "--vup {} -O {} {}",
      shell_word(plastimatch), c_arm.height, c_arm.width, c_arm.height * c_arm.pixel_mm, c_arm.width * c_arm.pixel_mm,
      c_arm.source_to_axis_mm, c_arm.source_to_image_mm, quoted(pose.isocenter_mm), quoted(-d), quoted(-g.v),
      shell_word(prefix), shell_word(mha));
  std::vector<double> projection_ms, process_ms;
  for (int run = 0; run < images; ++run) {
    std::remove(log.c_str());
    double s = 0;
    if (!timed_system(r.command + " > " + shell_word(log) + " 2>&1", &s)) {
      r.why = "plastimatch drr failed (" + log + ")";
      return r;
    }
    process_ms.push_back(1e3 * s);
    // "Total time: 0.66 secs": its time for the image, after reading the volume
    std::ifstream in(log);
    std::string line;
    double total_s = -1;
    while (std::getline(in, line))
      if (line.rfind("Total time:", 0) == 0) total_s = std::atof(line.c_str() + 11);
    if (total_s < 0) {
      r.why = "plastimatch drr printed no \"Total time\" (" + log + ")";
      return r;
    }
    projection_ms.push_back(1e3 * total_s);
  }
  r.images = images;
  std::sort(projection_ms.begin(), projection_ms.end());
  std::sort(process_ms.begin(), process_ms.end());
  r.per_image_ms = projection_ms[projection_ms.size() / 2];
  r.process_ms = process_ms[process_ms.size() / 2];
  xray::Image img;
  if (!read_pfm(prefix + "0000.pfm", &img, &r.why)) return r;
  if (img.width != reference.width || img.height != reference.height) {
    r.why = fmt::format("plastimatch's image is {} x {}, pcisim's {} x {}", img.width, img.height, reference.width,
                        reference.height);
    return r;
  }
  for (int row = 0; row < img.height; ++row)
    std::reverse(img.pixels.begin() + static_cast<ptrdiff_t>(row) * img.width,
                 img.pixels.begin() + static_cast<ptrdiff_t>(row + 1) * img.width);
  // correlation, the least-squares scale, and the RMSE after it
  const size_t n = img.pixels.size();
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0, peak = 0;
  for (size_t i = 0; i < n; ++i) {
    const double a = img.pixels[i], b = reference.pixels[i];
    sa += a;
    sb += b;
    saa += a * a;
    sbb += b * b;
    sab += a * b;
    peak = std::max(peak, b);
  }
  const double cov = sab - sa * sb / n, va = saa - sa * sa / n, vb = sbb - sb * sb / n;
  r.correlation = va > 0 && vb > 0 ? cov / std::sqrt(va * vb) : 0.0;
  r.scale = saa > 0 ? sab / saa : 0.0;
  double se = 0, se_first_row = 0;
  for (size_t i = 0; i < n; ++i) {
    const double e = r.scale * img.pixels[i] - reference.pixels[i];
    se += e * e;
    if (i < static_cast<size_t>(img.width)) se_first_row += e * e;
  }
  r.rmse_rel = peak > 0 ? std::sqrt(se / n) / peak : 0.0;
  r.first_row_share = se > 0 ? se_first_row / se : 0.0;
  r.ran = true;
  return r;
}

}  // namespace pcisim::bench
