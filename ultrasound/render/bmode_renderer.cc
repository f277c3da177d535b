#include "ultrasound/render/bmode_renderer.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "png/png_gray.h"
#include "ultrasound/echo/acoustic_model.h"

namespace pcisim::ultrasound {
namespace {
const Eigen::Vector3d kSpeckleLatticeShift(0.3183098861837907, 0.6180339887498949, 0.4142135623730950);
}  // namespace

void write_png(const std::string& path, const BModeImage& image) {
  png::write_png_gray8(path, image.width, image.height, image.pixels.data());
}

BModeRenderer::BModeRenderer(const anatomy::Volume& ct, const UsSettings& settings) : ct_(ct), settings_(settings) {
  validate(settings_);
  const std::string bad = anatomy::validate(ct);
  if (!bad.empty()) throw std::invalid_argument("ultrasound: the CT is not usable: " + bad);
  world_to_index_ = (ct.direction * ct.spacing_mm.asDiagonal()).inverse();
  // two wavelengths at the centre frequency in soft tissue (1540 m/s), at least one CT voxel
  pulse_mm_ = std::max(2.0 * 1.540 / settings_.frequency_mhz, ct.spacing_mm.maxCoeff());
  const size_t n = static_cast<size_t>(settings_.width_px) * settings_.height_px;
  offset_lateral_.resize(n);
  offset_beam_.resize(n);
  hu_.resize(n);
  z_.resize(n);
  speckle_.resize(n);
  echo_.resize(n);
  beam_.width = image_.width = settings_.width_px;
  beam_.height = image_.height = settings_.height_px;
  beam_.pixels.resize(n);
  image_.pixels.resize(n);
  if (settings_.geometry == ProbeGeometry::kCurvilinear) {
    convert_index_.resize(n);
    convert_fx_.resize(n);
    convert_fy_.resize(n);
  }
  build_geometry();
}

void BModeRenderer::set_imaging(double depth_mm, double gain_db) {
  if (depth_mm == settings_.depth_mm && gain_db == settings_.gain_db) return;
  UsSettings next = settings_;
  next.depth_mm = depth_mm;
  next.gain_db = gain_db;
  validate(next);
  const bool deeper = depth_mm != settings_.depth_mm;
  settings_ = next;
  if (deeper) build_geometry();
}

// each pixel's place in the probe's frame and, for a curvilinear probe, its display pixel's
// beam-space cell: both depend on the depth (sizes do not: nothing is allocated here)
void BModeRenderer::build_geometry() {
  const int w = settings_.width_px, h = settings_.height_px;
  ProbePose unit;  // origin 0, beam y, lateral x
  for (int c = 0; c < w; ++c)
    for (int r = 0; r < h; ++r) {
      const Eigen::Vector3d p = pixel_to_world(settings_, unit, c, r);
      offset_lateral_[static_cast<size_t>(c) * h + r] = p.x();
      offset_beam_[static_cast<size_t>(c) * h + r] = p.y();
    }
  if (settings_.geometry != ProbeGeometry::kCurvilinear) return;
  std::fill(convert_index_.begin(), convert_index_.end(), -1);
  std::fill(convert_fx_.begin(), convert_fx_.end(), 0.0f);
  std::fill(convert_fy_.begin(), convert_fy_.end(), 0.0f);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      double bc = 0, br = 0;
      if (!display_to_beam(settings_, c, r, &bc, &br)) continue;
      bc = std::clamp(bc, 0.0, w - 1.0);
      br = std::clamp(br, 0.0, h - 1.0);
      const int c0 = std::min(static_cast<int>(bc), w - 2), r0 = std::min(static_cast<int>(br), h - 2);
      const size_t k = static_cast<size_t>(r) * w + c;
      convert_index_[k] = r0 * w + c0;
      convert_fx_[k] = static_cast<float>(bc - c0);
      convert_fy_[k] = static_cast<float>(br - r0);
    }
}

// curvilinear display: bilinear in the beam-space grey levels, black outside the fan
void BModeRenderer::scan_convert() {
  const int w = settings_.width_px;
  for (size_t k = 0; k < image_.pixels.size(); ++k) {
    const int i = convert_index_[k];
    if (i < 0) {
      image_.pixels[k] = 0;
      continue;
    }
    const float fx = convert_fx_[k], fy = convert_fy_[k];
    const uint8_t* p = &beam_.pixels[i];
    const float v = (p[0] * (1 - fx) + p[1] * fx) * (1 - fy) + (p[w] * (1 - fx) + p[w + 1] * fx) * fy;
    image_.pixels[k] = static_cast<uint8_t>(std::lround(v));
  }
}

void BModeRenderer::set_mesh(const TetSnapshot& mesh) {
  locator_.build(mesh);
  have_mesh_ = true;
}

// trilinear HU at a CT point; outside the volume the nearest edge voxel (no artificial boundary)
double BModeRenderer::sample_hu(const Eigen::Vector3d& p_mm) const {
  const Eigen::Vector3d u = world_to_index_ * (p_mm - ct_.origin_mm);
  int64_t i0[3];
  double f[3];
  for (int k = 0; k < 3; ++k) {
    const double x = std::clamp(u[k], 0.0, static_cast<double>(ct_.dims[k] - 1));
    i0[k] = std::min<int64_t>(static_cast<int64_t>(x), std::max<int64_t>(ct_.dims[k] - 2, 0));
    f[k] = x - static_cast<double>(i0[k]);
  }
  const int64_t i1[3] = {std::min(i0[0] + 1, ct_.dims[0] - 1), std::min(i0[1] + 1, ct_.dims[1] - 1),
                         std::min(i0[2] + 1, ct_.dims[2] - 1)};
  auto v = [&](int64_t i, int64_t j, int64_t k) { return static_cast<double>(ct_.hu(i, j, k)); };
  const double c00 = v(i0[0], i0[1], i0[2]) * (1 - f[0]) + v(i1[0], i0[1], i0[2]) * f[0];
  const double c10 = v(i0[0], i1[1], i0[2]) * (1 - f[0]) + v(i1[0], i1[1], i0[2]) * f[0];
  const double c01 = v(i0[0], i0[1], i1[2]) * (1 - f[0]) + v(i1[0], i0[1], i1[2]) * f[0];
  const double c11 = v(i0[0], i1[1], i1[2]) * (1 - f[0]) + v(i1[0], i1[1], i1[2]) * f[0];
  const double c0 = c00 * (1 - f[1]) + c10 * f[1], c1 = c01 * (1 - f[1]) + c11 * f[1];
  return c0 * (1 - f[2]) + c1 * f[2];
}

const BModeImage& BModeRenderer::render(const ProbePose& pose, uint64_t seed, const TetSnapshot* deformed) {
  validate(pose);
  const bool mapped = deformed != nullptr;
  if (mapped) {
    if (!have_mesh_) set_mesh(*deformed);
    locator_.refit(*deformed);
  }
  const Eigen::Vector3d b = pose.beam.normalized();
  const Eigen::Vector3d l = (pose.lateral - pose.lateral.dot(b) * b).normalized();
  const int w = settings_.width_px, h = settings_.height_px;
  for (int c = 0; c < w; ++c) {
    for (int r = 0; r < h; ++r) {
      const size_t n = static_cast<size_t>(c) * h + r;
      const Eigen::Vector3d p = pose.origin_mm + offset_lateral_[n] * l + offset_beam_[n] * b;
      Eigen::Vector3d q = p;
      if (mapped && !locator_.to_rest(p, &q)) q = p;
      hu_[n] = sample_hu(q);
      z_[n] = impedance_mrayl(hu_[n]);
      // the lattice is shifted by irrational fractions of a cell: an image plane at round
      // coordinates (z = 0) would otherwise lie on cell faces, where rounding picks either side
      const Eigen::Vector3d cell = (q / settings_.speckle_cell_mm + kSpeckleLatticeShift).array().floor();
      speckle_[n] =
          speckle(seed, static_cast<int64_t>(cell[0]), static_cast<int64_t>(cell[1]), static_cast<int64_t>(cell[2]));
    }
    render_scanline(c);
  }
  if (settings_.geometry == ProbeGeometry::kLinear) return beam_;
  scan_convert();
  return image_;
}

// Along one scanline (samples j at depth d_j = (j + 1/2) dx):
//   R_j = ((Z(d_j + p/2) - Z(d_j - p/2)) / (Z(d_j + p/2) + Z(d_j - p/2)))^2   (p: pulse length;
//         the impedance change across one pulse, so the echo does not depend on the sampling)
//   T_{j+1} = T_j (1 - R_j)^(dx / p)                                   (one-way transmission)
//   L_j = sum_{i<j} a_i dx + a_j dx / 2,  a_i = alpha(HU_i) f          (one-way loss, dB)
//   I_j = T_j^2 10^(-2 L_j / 10) (R_j + sigma(HU_j) s_j)               (round trip)
// [Goksel & Salcudean 2009: reflection + scattering, attenuated; shadowing through T]
void BModeRenderer::render_scanline(int column) {
  const int h = settings_.height_px, w = settings_.width_px;
  const double dx_mm = settings_.depth_mm / h, dx_cm = dx_mm / 10.0;
  const double half = 0.5 * pulse_mm_ / dx_mm;  // half window in samples
  const double* z = &z_[static_cast<size_t>(column) * h];
  const double* hu = &hu_[static_cast<size_t>(column) * h];
  const double* spk = &speckle_[static_cast<size_t>(column) * h];
  auto z_at = [&](double s) {
    s = std::clamp(s, 0.0, static_cast<double>(h - 1));
    const int i = std::min(static_cast<int>(s), h - 2);
    const double f = s - i;
    return z[i] * (1 - f) + z[i + 1] * f;
  };
  const double step_exponent = dx_mm / pulse_mm_;
  double transmitted = 1.0, loss_db = 0.0;
  for (int j = 0; j < h; ++j) {
    const double a_db = attenuation_db(settings_.attenuation_db_per_cm_mhz, hu[j], settings_.frequency_mhz, dx_cm);
    const double to_centre_db = loss_db + 0.5 * a_db;
    const double refl = reflection(z_at(j - half), z_at(j + half));
    const double intensity =
        transmitted * transmitted * std::pow(10.0, -2.0 * to_centre_db / 10.0) * (refl + backscatter(hu[j]) * spk[j]);
    const size_t out = static_cast<size_t>(j) * w + column;
    echo_[out] = static_cast<float>(intensity);
    const double depth_cm = (j + 0.5) * dx_cm;
    beam_.pixels[out] = log_compress(brightness_db(intensity, settings_.gain_db, settings_.tgc_db_per_cm, depth_cm),
                                     settings_.dynamic_range_db);
    transmitted *= std::pow(1.0 - refl, step_exponent);
    loss_db += a_db;
  }
}

}  // namespace pcisim::ultrasound
