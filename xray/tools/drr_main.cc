// pcisim-drr: digitally reconstructed radiographs (line integrals of attenuation) from a CT volume,
// and the procedural thorax phantom as a volume file. Arguments are parsed by hand so the tool
// builds wherever the library does (the GPU machine has no CLI11).
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "xray/frame/png_writer.h"
#include "xray/geometry/detector_geometry.h"
#include "anatomy/phantom/thorax_phantom.h"
#include "xray/projectors/attenuation_volume.h"
#include "xray/projectors/siddon_projector.h"
#include "xray/projectors/trilinear_projector.h"
#ifdef PCISIM_HAVE_OSMESA
#include "xray/projectors/gl/gl_projector.h"
#endif
#include "anatomy/volume/volume_io.h"
#ifdef PCISIM_HAVE_CUDA
#include "xray/projectors/cuda_projector.h"
#endif

namespace {

using namespace pcisim::xray;
namespace anatomy = pcisim::anatomy;

constexpr const char* kHelp =
    R"(pcisim-drr: X-ray line integrals (DRRs) from a CT volume, or the procedural phantom as a file.

Render:
  pcisim-drr --volume FILE --source x,y,z --detector-center x,y,z --detector-u x,y,z
             --detector-v x,y,z --pixel-mm P --size W,H --projector exact|cpu|gl|cuda
             [--step VOXELS] [--mu-water M] [--threads N] --out PREFIX

  All positions are in the volume's physical frame (mm; patient LPS for DICOM-derived data).
  --volume FILE          .mha, .mhd, .nrrd or .nhdr, voxels in Hounsfield units
  --source x,y,z         the X-ray focal spot
  --detector-center x,y,z  centre of the detector plane
  --detector-u x,y,z     unit vector along image columns (c grows along u)
  --detector-v x,y,z     unit vector along image rows (r grows along v), perpendicular to u
  --pixel-mm P           pixel pitch (mm), > 0
  --size W,H             detector pixels
      Pixel (c, r) has its centre at detector_center + (c - (W-1)/2) P u + (r - (H-1)/2) P v;
      its value is the integral of mu along the segment from the source to that centre.
  --projector NAME       exact: Siddon/Jacobs voxel traversal, nearest-voxel mu (the reference)
                         cpu:   trilinear ray marching on all cores, empty bricks skipped
                         cuda:  the same marcher on the GPU (builds with CUDA only)
  --step VOXELS          marching step for cpu/cuda, in voxels (default 0.5)
  --mu-water M           attenuation of water in 1/mm (default 0.02); mu = M (1 + HU/1000),
                         HU below -800 counted as air (mu = 0)
  --threads N            CPU threads (default: all cores)
  --out PREFIX           writes PREFIX.f32 (float32 little-endian line integrals, row-major,
                         row 0 first, nothing else), PREFIX.json (geometry, projector, timing)
                         and PREFIX.png (8-bit preview: dark = more attenuation; skipped with a
                         message when built without libpng)

Phantom:
  pcisim-drr --write-phantom FILE [--seed N] [--size X,Y,Z] [--spacing MM] [--no-contrast]
             [--contrast-hu HU]
  --write-phantom FILE   .mha, .mhd or .nrrd: the seeded thorax CT (int16 HU, LPS, heart centre
                         at the origin; see docs/xray.md)
  --seed N               anatomy seed, also of the coronary tree (default 1)
  --size X,Y,Z           voxels (default 512,512,256)
  --spacing MM           isotropic voxel size (default 0.7)
  --no-contrast          coronary lumens hold blood instead of iodine
  --contrast-hu HU       HU of iodine-filled lumens (default 400)

Exit status: 0 on success, 2 on a bad argument (the message names it), 1 on any other failure.
)";

struct ArgError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

[[noreturn]] void bad(const std::string& name, const std::string& expected, const std::string& got) {
  throw ArgError(fmt::format("{}: expected {}, got '{}'", name, expected, got));
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  size_t start = 0;
  for (;;) {
    const size_t comma = s.find(',', start);
    out.push_back(s.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) return out;
    start = comma + 1;
  }
}

bool to_double(const std::string& s, double* v) {
  if (s.empty()) return false;
  char* end = nullptr;
  *v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(*v);
}

bool to_int(const std::string& s, long long* v) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), *v);
  return !s.empty() && r.ec == std::errc() && r.ptr == s.data() + s.size();
}

Eigen::Vector3d vec3(const std::string& name, const std::string& s) {
  const auto parts = split(s);
  Eigen::Vector3d v;
  if (parts.size() != 3 || !to_double(parts[0], &v.x()) || !to_double(parts[1], &v.y()) ||
      !to_double(parts[2], &v.z())) {
    bad(name, "three numbers x,y,z", s);
  }
  return v;
}

double positive(const std::string& name, const std::string& s) {
  double v = 0;
  if (!to_double(s, &v) || !(v > 0)) bad(name, "a number > 0", s);
  return v;
}

std::vector<long long> positive_ints(const std::string& name, const std::string& s, size_t n, const char* what) {
  const auto parts = split(s);
  std::vector<long long> out(parts.size());
  bool ok = parts.size() == n;
  for (size_t i = 0; ok && i < n; ++i) ok = to_int(parts[i], &out[i]) && out[i] > 0 && out[i] <= 100000;
  if (!ok) bad(name, what, s);
  return out;
}

struct Args {
  std::map<std::string, std::string> values;
  std::vector<std::string> flags;
};

Args parse(int argc, char** argv) {
  static const std::vector<std::string> with_value = {
      "--volume",    "--source",     "--detector-center", "--detector-u", "--detector-v", "--pixel-mm",      "--size",
      "--projector", "--step",       "--mu-water",        "--threads",    "--out",        "--write-phantom", "--seed",
      "--spacing",   "--contrast-hu"};
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (k == "--help" || k == "-h" || k == "--no-contrast") {
      a.flags.push_back(k);
    } else if (std::find(with_value.begin(), with_value.end(), k) != with_value.end()) {
      if (i + 1 >= argc) throw ArgError(fmt::format("{}: expected a value after it", k));
      if (a.values.count(k)) throw ArgError(fmt::format("{}: given twice", k));
      a.values[k] = argv[++i];
    } else {
      throw ArgError(fmt::format("{}: unknown argument (see --help)", k));
    }
  }
  return a;
}

const std::string& need(const Args& a, const char* k, const char* what) {
  const auto it = a.values.find(k);
  if (it == a.values.end()) throw ArgError(fmt::format("{}: missing; expected {}", k, what));
  return it->second;
}

bool has_flag(const Args& a, const char* f) {
  return std::find(a.flags.begin(), a.flags.end(), f) != a.flags.end();
}

int write_phantom(const Args& a) {
  const std::string path = a.values.at("--write-phantom");
  for (const char* k : {"--volume", "--source", "--detector-center", "--detector-u", "--detector-v", "--pixel-mm",
                        "--projector", "--step", "--mu-water", "--out"}) {
    if (a.values.count(k)) throw ArgError(fmt::format("{}: not used with --write-phantom", k));
  }
  anatomy::ThoraxPhantomSpec spec;
  if (a.values.count("--seed")) {
    long long s = 0;
    if (!to_int(a.values.at("--seed"), &s) || s < 0 || s > 0xffffffffLL)
      bad("--seed", "an integer in [0, 2^32)", a.values.at("--seed"));
    spec.seed = static_cast<uint32_t>(s);
  }
  if (a.values.count("--size")) {
    const auto d = positive_ints("--size", a.values.at("--size"), 3, "X,Y,Z (three positive integers)");
    spec.dims = {d[0], d[1], d[2]};
  }
  if (a.values.count("--spacing")) spec.spacing_mm = positive("--spacing", a.values.at("--spacing"));
  if (a.values.count("--contrast-hu")) {
    double hu = 0;
    if (!to_double(a.values.at("--contrast-hu"), &hu) || hu < -1000 || hu > 3000)
      bad("--contrast-hu", "HU in [-1000, 3000]", a.values.at("--contrast-hu"));
    spec.contrast_hu = hu;
  }
  spec.contrast = !has_flag(a, "--no-contrast");
  const auto t0 = std::chrono::steady_clock::now();
  const anatomy::Volume v = anatomy::make_thorax_phantom(spec);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const std::string l = path.size() >= 5 ? path.substr(path.size() - 5) : path;
  if (l == ".nrrd") {
    anatomy::write_nrrd(v, path);
  } else {
    anatomy::write_metaimage(v, path);  // rejects other extensions with a message
  }
  std::printf("pcisim-drr: wrote %s (%lldx%lldx%lld at %.3g mm, seed %u, built in %.0f ms)\n", path.c_str(),
              (long long)v.dims[0], (long long)v.dims[1], (long long)v.dims[2], spec.spacing_mm, spec.seed, ms);
  return 0;
}

std::string json_vec(const Eigen::Vector3d& v) {
  return fmt::format("[{:.17g}, {:.17g}, {:.17g}]", v.x(), v.y(), v.z());
}

int render(const Args& a) {
  for (const char* k : {"--seed", "--spacing", "--contrast-hu"}) {
    if (a.values.count(k)) throw ArgError(fmt::format("{}: only used with --write-phantom", k));
  }
  if (has_flag(a, "--no-contrast")) throw ArgError("--no-contrast: only used with --write-phantom");
  const std::string volume_path = need(a, "--volume", "a volume file (.mha, .mhd, .nrrd, .nhdr)");
  DetectorGeometry g;
  g.source_mm = vec3("--source", need(a, "--source", "x,y,z"));
  g.center_mm = vec3("--detector-center", need(a, "--detector-center", "x,y,z"));
  const Eigen::Vector3d u = vec3("--detector-u", need(a, "--detector-u", "a unit vector x,y,z"));
  const Eigen::Vector3d v = vec3("--detector-v", need(a, "--detector-v", "a unit vector x,y,z"));
  if (std::abs(u.norm() - 1) > 1e-3)
    bad("--detector-u", "a unit vector (length 1 within 1e-3)", a.values.at("--detector-u"));
  if (std::abs(v.norm() - 1) > 1e-3)
    bad("--detector-v", "a unit vector (length 1 within 1e-3)", a.values.at("--detector-v"));
  if (std::abs(u.normalized().dot(v.normalized())) > 1e-3) {
    bad("--detector-v", "a vector perpendicular to --detector-u (|u.v| <= 1e-3)", a.values.at("--detector-v"));
  }
  g.u = u.normalized();
  g.v = v.normalized();
  g.pixel_mm = positive("--pixel-mm", need(a, "--pixel-mm", "the pixel pitch in mm"));
  const auto size = positive_ints("--size", need(a, "--size", "W,H"), 2, "W,H (two positive integers <= 100000)");
  g.width = static_cast<int>(size[0]);
  g.height = static_cast<int>(size[1]);
  if (std::abs(g.u.cross(g.v).dot(g.center_mm - g.source_mm)) < 1e-6) {
    bad("--source", "a point off the detector plane", a.values.at("--source"));
  }
  const std::string projector = need(a, "--projector", "exact, cpu, gl or cuda");
  if (projector != "exact" && projector != "cpu" && projector != "gl" && projector != "cuda")
    bad("--projector", "exact, cpu, gl or cuda", projector);
  TrilinearOptions opt;
  if (a.values.count("--step")) {
    if (projector == "exact") throw ArgError("--step: only used by the cpu, gl and cuda projectors");
    opt.step_voxels = positive("--step", a.values.at("--step"));
    if (opt.step_voxels < kMinSceneStepVoxels || opt.step_voxels > kMaxSceneStepVoxels)
      bad("--step", fmt::format("a step in [{}, {}] voxels", kMinSceneStepVoxels, kMaxSceneStepVoxels),
          a.values.at("--step"));
  }
  AttenuationParams params;
  if (a.values.count("--mu-water")) params.mu_water_per_mm = positive("--mu-water", a.values.at("--mu-water"));
  if (a.values.count("--threads")) {
    long long t = 0;
    if (!to_int(a.values.at("--threads"), &t) || t < 1 || t > 1024)
      bad("--threads", "an integer in [1, 1024]", a.values.at("--threads"));
    opt.threads = static_cast<int>(t);
  }
  const std::string prefix = need(a, "--out", "an output prefix");
#ifndef PCISIM_HAVE_CUDA
  if (projector == "cuda") bad("--projector", "exact, cpu or gl (this build has no CUDA)", projector);
#endif
#ifndef PCISIM_HAVE_OSMESA
  if (projector == "gl") bad("--projector", "exact, cpu or cuda (this build has no OSMesa)", projector);
#endif

  anatomy::Volume volume;
  try {
    volume = anatomy::read_volume(volume_path);
  } catch (const anatomy::VolumeIoError& e) {
    throw ArgError(fmt::format("--volume: {}", e.what()));
  }
  const AttenuationVolume att(volume, params);
  Image image;
  image.resize(g.width, g.height);
  double ms = 0;
  std::string device = "cpu";
  auto timed = [&](auto&& fn) {
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  };
  if (projector == "exact") {
    SiddonProjector p(att, opt.threads);
    timed([&] { p.project(g, &image); });
  } else if (projector == "cpu") {
    TrilinearProjector p(att, opt);
    timed([&] { p.project(g, &image); });
  } else if (projector == "gl") {
#ifdef PCISIM_HAVE_OSMESA
    GlProjector p(att, opt.step_voxels);
    device = "OSMesa";
    timed([&] { p.project(g, &image); });
#endif
  } else {
#ifdef PCISIM_HAVE_CUDA
    std::string why;
    if (!CudaTrilinearProjector::available(&why)) throw std::runtime_error("--projector cuda: " + why);
    CudaTrilinearProjector p(att, opt);
    device = p.device_name();
    timed([&] { p.project(g, &image); });
#endif
  }

  {
    std::ofstream f(prefix + ".f32", std::ios::binary);
    f.write(reinterpret_cast<const char*>(image.pixels.data()),
            static_cast<std::streamsize>(image.pixels.size() * sizeof(float)));
    if (!f) throw std::runtime_error(prefix + ".f32: write failed");
  }
  float peak = 0;
  for (float x : image.pixels) peak = std::max(peak, x);
  {
    std::ofstream f(prefix + ".json");
    f << "{\n";
    f << fmt::format("  \"format\": \"pcisim-drr\",\n  \"version\": 1,\n");
    f << fmt::format("  \"volume\": \"{}\",\n", volume_path);
    f << fmt::format("  \"volume_dims\": [{}, {}, {}],\n", volume.dims[0], volume.dims[1], volume.dims[2]);
    f << fmt::format("  \"volume_spacing_mm\": {},\n", json_vec(volume.spacing_mm));
    f << fmt::format("  \"source_mm\": {},\n  \"detector_center_mm\": {},\n", json_vec(g.source_mm),
                     json_vec(g.center_mm));
    f << fmt::format("  \"detector_u\": {},\n  \"detector_v\": {},\n", json_vec(g.u), json_vec(g.v));
    f << fmt::format("  \"pixel_mm\": {:.17g},\n  \"width\": {},\n  \"height\": {},\n", g.pixel_mm, g.width, g.height);
    f << fmt::format("  \"projector\": \"{}\",\n", projector);
    f << fmt::format("  \"step_voxels\": {},\n",
                     projector == "exact" ? std::string("null") : fmt::format("{:.17g}", opt.step_voxels));
    f << fmt::format("  \"mu_water_per_mm\": {:.17g},\n  \"air_below_hu\": {:.17g},\n", params.mu_water_per_mm,
                     params.air_below_hu);
    f << fmt::format("  \"device\": \"{}\",\n  \"render_ms\": {:.3f},\n", device, ms);
    f << fmt::format("  \"max_line_integral\": {:.9g},\n", peak);
    f << "  \"data\": {\"file\": \"" << prefix.substr(prefix.find_last_of('/') + 1)
      << ".f32\", \"type\": \"float32\", \"endian\": \"little\", \"order\": \"row-major, row 0 first\"}\n}\n";
    if (!f) throw std::runtime_error(prefix + ".json: write failed");
  }
  std::string why;
  if (write_png_preview(image, prefix + ".png", &why)) {
    std::printf("pcisim-drr: wrote %s.f32, %s.json, %s.png (%s, %.1f ms, max line integral %.4g)\n", prefix.c_str(),
                prefix.c_str(), prefix.c_str(), projector.c_str(), ms, peak);
  } else {
    std::printf("pcisim-drr: wrote %s.f32, %s.json (%s, %.1f ms); PNG skipped: %s\n", prefix.c_str(), prefix.c_str(),
                projector.c_str(), ms, why.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Args a = parse(argc, argv);
    if (has_flag(a, "--help") || has_flag(a, "-h") || argc == 1) {
      std::fputs(kHelp, stdout);
      return argc == 1 ? 2 : 0;
    }
    return a.values.count("--write-phantom") ? write_phantom(a) : render(a);
  } catch (const ArgError& e) {
    std::fprintf(stderr, "pcisim-drr: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pcisim-drr: %s\n", e.what());
    return 1;
  }
}
