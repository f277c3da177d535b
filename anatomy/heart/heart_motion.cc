#include "anatomy/heart/heart_motion.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace pcisim::anatomy {
namespace {

constexpr std::string_view kMagic = "pcisim-heart-motion 1";

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw std::invalid_argument(name + ": " + what);
}

// little-endian float32 <-> host float, so the file reads the same on every platform
float load_le(const char* p) {
  uint32_t u = 0;
  for (int b = 3; b >= 0; --b) u = (u << 8) | static_cast<unsigned char>(p[b]);
  return std::bit_cast<float>(u);
}
void store_le(float f, char* p) {
  const uint32_t u = std::bit_cast<uint32_t>(f);
  for (int b = 0; b < 4; ++b) p[b] = static_cast<char>((u >> (8 * b)) & 0xff);
}

}  // namespace

HeartMotion::HeartMotion(const MotionGrid& grid, int frames, double cycle_s, std::vector<float> data_m)
    : grid_(grid), frames_(frames), cycle_s_(cycle_s), data_m_(std::move(data_m)) {
  const std::string n = "heart motion";
  if (frames < 2) fail(n, "frames must be >= 2, got " + std::to_string(frames));
  if (!(cycle_s > 0.0) || !std::isfinite(cycle_s)) fail(n, "cycle_s must be > 0");
  if (!grid.origin_m.allFinite()) fail(n, "origin_m must be finite");
  if (!(grid.spacing_m.minCoeff() > 0.0) || !grid.spacing_m.allFinite()) fail(n, "spacing_m must be > 0 on every axis");
  if (grid.dims.minCoeff() < 2) fail(n, "dims must be >= 2 on every axis");
  const size_t want = static_cast<size_t>(frames) * grid.node_count() * 3;
  if (data_m_.size() != want)
    fail(n, "data holds " + std::to_string(data_m_.size()) + " floats, frames * nodes * 3 = " + std::to_string(want));
  for (size_t i = 0; i < data_m_.size(); ++i)
    if (!std::isfinite(data_m_[i]))
      fail(n, "data: non-finite displacement in frame " + std::to_string(i / (3 * grid.node_count())));
}

Eigen::Vector3d HeartMotion::node_displacement_m(int frame, int i, int j, int k) const {
  const size_t node = (static_cast<size_t>(k) * grid_.dims.y() + j) * grid_.dims.x() + i;
  const float* d = data_m_.data() + 3 * (static_cast<size_t>(frame) * grid_.node_count() + node);
  return {d[0], d[1], d[2]};
}

// trilinear, the point clamped into the grid's box (outside, the nearest boundary value holds)
Eigen::Vector3d HeartMotion::frame_displacement_m(int frame, const Eigen::Vector3d& rest_m) const {
  int i0[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double u = std::clamp((rest_m[a] - grid_.origin_m[a]) / grid_.spacing_m[a], 0.0, double(grid_.dims[a] - 1));
    i0[a] = std::min(static_cast<int>(u), grid_.dims[a] - 2);
    f[a] = u - i0[a];
  }
  Eigen::Vector3d out = Eigen::Vector3d::Zero();
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const double w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
    out += w * node_displacement_m(frame, i0[0] + dx, i0[1] + dy, i0[2] + dz);
  }
  return out;
}

HeartMotion::FrameWeights HeartMotion::frame_weights(double phase) const {
  const double t = (phase - std::floor(phase)) * frames_;
  const int f1 = std::min(static_cast<int>(t), frames_ - 1);
  const double u = t - f1;
  // uniform Catmull-Rom: passes through every frame, C1 across frames and across the cycle's end
  const double u2 = u * u, u3 = u2 * u;
  return {{(f1 + frames_ - 1) % frames_, f1, (f1 + 1) % frames_, (f1 + 2) % frames_},
          {0.5 * (-u3 + 2 * u2 - u), 0.5 * (3 * u3 - 5 * u2 + 2), 0.5 * (-3 * u3 + 4 * u2 + u), 0.5 * (u3 - u2)}};
}

Eigen::Vector3d HeartMotion::displacement_m(const Eigen::Vector3d& rest_m, double phase) const {
  if (!std::isfinite(phase) || !rest_m.allFinite()) return Eigen::Vector3d::Zero();
  const FrameWeights w = frame_weights(phase);
  Eigen::Vector3d out = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k) out += w.weight[k] * frame_displacement_m(w.frame[k], rest_m);
  return out;
}

std::string HeartMotion::serialize() const {
  // shortest text that reads back to the same double
  auto num = [](double v) {
    char buf[32];
    return std::string(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
  };
  auto vec = [&](const Eigen::Vector3d& v) { return num(v.x()) + ' ' + num(v.y()) + ' ' + num(v.z()); };
  std::string out = std::string(kMagic) + "\nframes " + std::to_string(frames_) + "\ncycle_s " + num(cycle_s_) +
                    "\norigin_m " + vec(grid_.origin_m) + "\nspacing_m " + vec(grid_.spacing_m) + "\ndims " +
                    std::to_string(grid_.dims.x()) + ' ' + std::to_string(grid_.dims.y()) + ' ' +
                    std::to_string(grid_.dims.z()) + "\ndata float32-le\n";
  const size_t header = out.size();
  out.resize(header + 4 * data_m_.size());
  for (size_t i = 0; i < data_m_.size(); ++i) store_le(data_m_[i], out.data() + header + 4 * i);
  return out;
}

HeartMotion HeartMotion::parse(std::string_view bytes, const std::string& name) {
  size_t pos = 0;
  int line_no = 0;
  // the next header line, which must start with key; returns the rest
  auto line = [&](std::string_view key) -> std::string {
    if (pos >= bytes.size()) fail(name, "header ends before field '" + std::string(key) + "'");
    const size_t end = bytes.find('\n', pos);
    if (end == std::string_view::npos) fail(name, "header ends before field '" + std::string(key) + "'");
    std::string_view l = bytes.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    const std::string where = " (line " + std::to_string(line_no) + ")";
    if (l.substr(0, key.size()) != key || (l.size() > key.size() && l[key.size()] != ' '))
      fail(name, "expected field '" + std::string(key) + "'" + where + ", got '" + std::string(l.substr(0, 40)) + "'");
    return std::string(l.substr(std::min(l.size(), key.size() + 1)));
  };
  auto numbers = [&](std::string_view key, int count, std::vector<double>* out) {
    const std::string rest = line(key);
    std::istringstream in(rest);
    out->assign(count, 0.0);
    for (int i = 0; i < count; ++i)
      if (!(in >> (*out)[i]) || !std::isfinite((*out)[i]))
        fail(name,
             "field '" + std::string(key) + "' needs " + std::to_string(count) + " finite numbers, got '" + rest + "'");
    std::string extra;
    if (in >> extra) fail(name, "field '" + std::string(key) + "' has extra text '" + extra + "'");
  };

  if (bytes.substr(0, kMagic.size()) != kMagic || bytes.size() <= kMagic.size() ||
      (bytes[kMagic.size()] != '\n' && bytes[kMagic.size()] != '\r'))
    fail(name, "magic line must be '" + std::string(kMagic) + "'");
  line(kMagic);
  std::vector<double> v;
  numbers("frames", 1, &v);
  if (v[0] < 2 || v[0] != std::floor(v[0]) || v[0] > 1e6) fail(name, "field 'frames' must be an integer >= 2");
  const int frames = static_cast<int>(v[0]);
  numbers("cycle_s", 1, &v);
  if (!(v[0] > 0.0)) fail(name, "field 'cycle_s' must be > 0");
  const double cycle_s = v[0];
  MotionGrid grid;
  numbers("origin_m", 3, &v);
  grid.origin_m = {v[0], v[1], v[2]};
  numbers("spacing_m", 3, &v);
  if (!(std::min({v[0], v[1], v[2]}) > 0.0)) fail(name, "field 'spacing_m' must be > 0 on every axis");
  grid.spacing_m = {v[0], v[1], v[2]};
  numbers("dims", 3, &v);
  for (double d : v)
    if (d < 2 || d != std::floor(d) || d > 1e5) fail(name, "field 'dims' must be integers >= 2");
  grid.dims = {int(v[0]), int(v[1]), int(v[2])};
  if (const std::string enc = line("data"); enc != "float32-le")
    fail(name, "field 'data' must say float32-le, got '" + enc + "'");

  // checked by division first: frames * nodes * 12 bytes wrapped size_t for a hostile header and
  // the wrapped size matched a short file
  const size_t have = bytes.size() - pos;
  const auto nodes = static_cast<size_t>(grid.node_count());
  if (nodes > have / 12 / static_cast<size_t>(frames) || 12 * nodes * static_cast<size_t>(frames) != have) {
    const double want = 12.0 * static_cast<double>(nodes) * frames;
    fail(name, "data: expected " + (want < 1e18 ? std::to_string(static_cast<size_t>(want)) : std::to_string(want)) +
                   " bytes (frames * dims * 3 float32), got " + std::to_string(have));
  }
  const size_t count = nodes * static_cast<size_t>(frames) * 3;
  std::vector<float> data(count);
  for (size_t i = 0; i < count; ++i) {
    data[i] = load_le(bytes.data() + pos + 4 * i);
    if (!std::isfinite(data[i]))
      fail(name, "data: non-finite displacement at frame " + std::to_string(i / (3 * grid.node_count())) + ", node " +
                     std::to_string((i / 3) % grid.node_count()));
  }
  return HeartMotion(grid, frames, cycle_s, std::move(data));
}

HeartMotion HeartMotion::read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open");
  std::ostringstream s;
  s << in.rdbuf();
  return parse(s.str(), path);
}

void HeartMotion::write(const std::string& path) const {
  std::ofstream out(path, std::ios::binary);
  const std::string bytes = serialize();
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) fail(path, "cannot write");
}

}  // namespace pcisim::anatomy
