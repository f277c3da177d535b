#include "modeling/motion/synthetic_cine.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <thread>

#include "anatomy/heart/heart_frame.h"
#include "anatomy/heart/template_heart_surface.h"
#include "anatomy/volume/volume_io.h"

namespace pcisim::modeling {
namespace {

using Eigen::Vector3d;

// bright-blood cine (bSSFP) on a 0..1 scale
constexpr float kBloodIntensity = 1.0f;
constexpr float kMyocardiumIntensity = 0.25f;
constexpr float kFatIntensity = 0.85f;
constexpr float kOtherIntensity = 0.4f;

constexpr int kMaxInversionSteps = 30;
constexpr double kInversionStopM = 1e-7;

// a cavity ellipsoid as (heart-frame point - centre) -> unit-sphere coordinates
struct Cavity {
  Vector3d centre_mm;
  Eigen::Matrix3d to_unit;  // diag(1 / semi-axes) * axes^T
  explicit Cavity(const anatomy::CavityEllipsoid& c)
      : centre_mm(c.centre_mm),
        to_unit(c.semi_axes_mm.cwiseInverse().asDiagonal() *
                Eigen::AngleAxisd(c.azimuth_rad, Vector3d::UnitZ()).toRotationMatrix().transpose()) {}
  bool contains(const Vector3d& h_mm) const { return (to_unit * (h_mm - centre_mm)).squaredNorm() <= 1.0; }
};

// the template in the heart frame; the heart's centre is the patient origin
// (template_heart_surface.cc writes vertex to_patient * (radius * u), no offset)
struct TemplateHeart {
  Eigen::Matrix3d patient_to_heart = anatomy::heart_to_patient().transpose();
  Cavity lv{anatomy::lv_cavity()};
  Cavity rv{anatomy::rv_cavity()};
};

const TemplateHeart& template_heart() {
  static const TemplateHeart heart;
  return heart;
}

uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

std::string bad(const char* field, const std::string& what, double got) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", got);
  return std::string(field) + ": " + what + ", got " + buf;
}

}  // namespace

CineTissue template_tissue(const Vector3d& rest_m, double fat_mm) {
  const TemplateHeart& heart = template_heart();
  const Vector3d h_mm = heart.patient_to_heart * rest_m * 1e3;
  if (heart.lv.contains(h_mm) || heart.rv.contains(h_mm)) return CineTissue::kBlood;
  const double r_mm = h_mm.norm();
  if (r_mm < 1e-9) return CineTissue::kMyocardium;
  const double epi_mm = anatomy::epicardial_radius_mm(h_mm / r_mm);
  if (r_mm <= epi_mm) return CineTissue::kMyocardium;
  // the fat layer measured radially from the heart's centre (the epicardium is near a sphere)
  if (r_mm <= epi_mm + fat_mm) return CineTissue::kFat;
  return CineTissue::kOther;
}

float cine_intensity(CineTissue tissue) {
  switch (tissue) {
    case CineTissue::kBlood:
      return kBloodIntensity;
    case CineTissue::kMyocardium:
      return kMyocardiumIntensity;
    case CineTissue::kFat:
      return kFatIntensity;
    case CineTissue::kOther:
      return kOtherIntensity;
  }
  return kOtherIntensity;
}

std::string validate(const CineSpec& s) {
  if (s.frames < 2 || s.frames > 200) return bad("frames", "must be 2..200", s.frames);
  static const char* const kVoxelNames[3] = {"voxel_mm.x", "voxel_mm.y", "voxel_mm.z"};
  for (int a = 0; a < 3; ++a)
    if (!(s.voxel_mm[a] >= 0.1 && s.voxel_mm[a] <= 20.0)) return bad(kVoxelNames[a], "must be 0.1..20", s.voxel_mm[a]);
  if (!(s.slice_thickness_mm >= 0.0 && s.slice_thickness_mm <= 50.0))
    return bad("slice_thickness_mm", "must be 0..50", s.slice_thickness_mm);
  if (!(s.margin_mm >= 0.0 && s.margin_mm <= 200.0)) return bad("margin_mm", "must be 0..200", s.margin_mm);
  if (!(s.fat_mm >= 0.0 && s.fat_mm <= 50.0)) return bad("fat_mm", "must be 0..50", s.fat_mm);
  if (!(s.noise_sigma >= 0.0 && s.noise_sigma <= 1.0)) return bad("noise_sigma", "must be 0..1", s.noise_sigma);
  if (s.supersample < 1 || s.supersample > 8) return bad("supersample", "must be 1..8", s.supersample);
  if (!(s.tag_amplitude >= 0.0 && s.tag_amplitude <= 1.0)) return bad("tag_amplitude", "must be 0..1", s.tag_amplitude);
  if (!(s.tag_wavelength_mm >= 1.0 && s.tag_wavelength_mm <= 100.0))
    return bad("tag_wavelength_mm", "must be 1..100", s.tag_wavelength_mm);
  return "";
}

Vector3d cine_rest_point_m(const anatomy::HeartMotion& truth, const Vector3d& x_m, double phase) {
  Vector3d r = x_m - truth.displacement_m(x_m, phase);
  for (int it = 0; it < kMaxInversionSteps; ++it) {
    const Vector3d next = x_m - truth.displacement_m(r, phase);
    const double step_m = (next - r).norm();
    r = next;
    if (step_m < kInversionStopM) break;
  }
  return r;
}

anatomy::Volume render_synthetic_cine_frame(const anatomy::HeartMotion& truth, const CineSpec& spec, int frame) {
  if (const std::string err = validate(spec); !err.empty()) throw std::invalid_argument(err);
  if (frame < 0 || frame >= spec.frames)
    throw std::invalid_argument("frame: must be 0.." + std::to_string(spec.frames - 1) + ", got " +
                                std::to_string(frame));

  // the grid: the template's bounding box plus the margin, centred on it
  const anatomy::HeartSurface surface = anatomy::template_heart_surface();
  Vector3d lo_mm = Vector3d::Constant(1e300), hi_mm = Vector3d::Constant(-1e300);
  for (const Vector3d& v : surface.vertices_mm) {
    lo_mm = lo_mm.cwiseMin(v);
    hi_mm = hi_mm.cwiseMax(v);
  }
  lo_mm.array() -= spec.margin_mm;
  hi_mm.array() += spec.margin_mm;
  std::array<int64_t, 3> dims{};
  for (int a = 0; a < 3; ++a) dims[a] = static_cast<int64_t>(std::ceil((hi_mm[a] - lo_mm[a]) / spec.voxel_mm[a])) + 1;
  const Vector3d extent_mm = Vector3d(dims[0] - 1, dims[1] - 1, dims[2] - 1).cwiseProduct(spec.voxel_mm);
  const Vector3d origin_mm = 0.5 * (lo_mm + hi_mm) - 0.5 * extent_mm;

  // sample offsets inside a voxel (mm): a regular supersample per axis; with a slice thickness
  // the z samples spread over the thickness instead, at least as dense as within a voxel
  const int n = spec.supersample;
  std::vector<double> off_x(n), off_y(n), off_z;
  for (int a = 0; a < n; ++a) {
    off_x[a] = ((a + 0.5) / n - 0.5) * spec.voxel_mm.x();
    off_y[a] = ((a + 0.5) / n - 0.5) * spec.voxel_mm.y();
  }
  const double span_z_mm = spec.slice_thickness_mm > 0 ? spec.slice_thickness_mm : spec.voxel_mm.z();
  const int nz = spec.slice_thickness_mm > 0
                     ? std::max(n, static_cast<int>(std::ceil(n * spec.slice_thickness_mm / spec.voxel_mm.z())))
                     : n;
  for (int c = 0; c < nz; ++c) off_z.push_back(((c + 0.5) / nz - 0.5) * span_z_mm);
  const double inv_samples = 1.0 / (static_cast<double>(n) * n * nz);

  const double phase = static_cast<double>(frame) / spec.frames;
  anatomy::Volume vol = anatomy::Volume::make(dims, spec.voxel_mm, origin_mm, anatomy::VoxelType::kFloat32);

  // each z-slice on its own: the voxels do not depend on which thread renders them
  std::atomic<int64_t> next_k{0};
  auto render_slices = [&] {
    for (int64_t k = next_k++; k < dims[2]; k = next_k++)
      for (int64_t j = 0; j < dims[1]; ++j)
        for (int64_t i = 0; i < dims[0]; ++i) {
          const Vector3d centre_mm = origin_mm + Vector3d(i, j, k).cwiseProduct(spec.voxel_mm);
          double sum = 0.0;
          for (double dz : off_z)
            for (double dy : off_y)
              for (double dx : off_x) {
                const Vector3d x_m = (centre_mm + Vector3d(dx, dy, dz)) * 1e-3;
                const Vector3d r_m = cine_rest_point_m(truth, x_m, phase);
                double value = cine_intensity(template_tissue(r_m, spec.fat_mm));
                if (spec.tag_amplitude > 0.0) {
                  const Vector3d a = r_m * (1e3 * 2.0 * std::numbers::pi / spec.tag_wavelength_mm);
                  value *= 1.0 + spec.tag_amplitude * std::sin(a.x()) * std::sin(a.y()) * std::sin(a.z());
                }
                sum += value;
              }
          vol.hu_f32[vol.linear_index(i, j, k)] = static_cast<float>(sum * inv_samples);
        }
  };
  const int workers = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, 2);
  std::vector<std::thread> pool;
  for (int w = 1; w < workers; ++w) pool.emplace_back(render_slices);
  render_slices();
  for (auto& t : pool) t.join();

  // noise in voxel order from this frame's own generator: a frame is reproducible alone
  if (spec.noise_sigma > 0) {
    std::mt19937_64 rng(splitmix64(spec.seed ^ splitmix64(static_cast<uint64_t>(frame))));
    std::normal_distribution<double> noise(0.0, spec.noise_sigma);
    for (float& v : vol.hu_f32) v = static_cast<float>(v + noise(rng));
  }
  return vol;
}

CineSequence render_synthetic_cine(const anatomy::HeartMotion& truth, const CineSpec& spec) {
  if (const std::string err = validate(spec); !err.empty()) throw std::invalid_argument(err);
  CineSequence out;
  out.cycle_s = truth.cycle_s();
  out.frames.reserve(spec.frames);
  for (int f = 0; f < spec.frames; ++f) out.frames.push_back(render_synthetic_cine_frame(truth, spec, f));
  return out;
}

void write_cine(const CineSequence& sequence, const std::string& dir) {
  std::filesystem::create_directories(dir);
  for (size_t f = 0; f < sequence.frames.size(); ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%03zu.nrrd", f);
    anatomy::write_nrrd(sequence.frames[f], (std::filesystem::path(dir) / name).string());
  }
}

}  // namespace pcisim::modeling
