#include "ultrasound/render/bmode_renderer.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "png/png_gray.h"
#include "ultrasound/echo/acoustic_model.h"
#include "ultrasound/echo/point_spread.h"

namespace pcisim::ultrasound {
void write_png(const std::string& path, const BModeImage& image) {
  png::write_png_gray8(path, image.width, image.height, image.pixels.data());
}

BModeRenderer::BModeRenderer(const anatomy::Volume& ct, const UsSettings& settings, const anatomy::TissueMap* tissue)
    : ct_(ct), settings_(settings), pool_((validate(settings), settings.threads)) {
  const std::string bad = anatomy::validate(ct);
  if (!bad.empty()) throw std::invalid_argument("ultrasound: the CT is not usable: " + bad);
  if (tissue) {
    if (const std::string why = anatomy::validate_tissue_map(*tissue, ct); !why.empty())
      throw std::invalid_argument("ultrasound: the tissue map is not usable: " + why);
    for (size_t i = 0; i < tissue->names.size(); ++i) {
      const TissueAcoustics* t = find_tissue_acoustics(tissue->names[i]);
      if (!t)
        throw std::invalid_argument("ultrasound: tissue \"" + tissue->names[i] + "\" (label " + std::to_string(i) +
                                    ") has no acoustic properties (known: " + known_tissue_names() + ")");
      label_acoustics_.push_back(acoustics_of(*t));
    }
    labels_ = &tissue->labels;
  }
  world_to_index_ = (ct.direction * ct.spacing_mm.asDiagonal()).inverse();
  // two wavelengths at the centre frequency in soft tissue (1540 m/s), at least one CT voxel
  voxel_mm_ = ct.spacing_mm.maxCoeff();
  pulse_mm_ = std::max(2.0 * 1.540 / settings_.frequency_mhz, voxel_mm_);
  const size_t n = static_cast<size_t>(settings_.width_px) * settings_.height_px;
  line_start_.resize(settings_.width_px);
  line_dir_.resize(settings_.width_px);
  z_.resize(n);
  path_ratio_.resize(n);
  attenuation_.resize(n);
  scatter_amplitude_.resize(n);
  scatterer_.resize(n);
  field_.resize(n);
  axial_.resize(n);
  echo_.resize(n);
  constexpr size_t taps = 2 * kMaxKernelHalf + 1;
  axial_kernel_.resize(taps);
  steep_kernel_.resize(taps);
  steepness_.resize(n);
  lateral_kernel_.resize(taps * settings_.height_px);
  lateral_half_.resize(settings_.height_px);
  line_spacing_mm_.resize(settings_.height_px);
  scatter_scale_.resize(settings_.height_px);
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

namespace {

// the tissue's scatterer field correlates over its lattice: two samples tau cells apart along a
// lattice axis correlate as the autocorrelation of the trilinear weight (a tent's with itself):
//   rho(x) = 1 - 3/2 x^2 + 3/4 |x|^3 (|x| <= 1),  (2 - |x|)^3 / 4 (1 <= |x| <= 2),  0 beyond
double lattice_correlation(double x) {
  x = std::abs(x);
  if (x >= 2.0) return 0.0;
  if (x >= 1.0) return 0.25 * (2.0 - x) * (2.0 - x) * (2.0 - x);
  return 1.0 - 1.5 * x * x + 0.75 * x * x * x;
}

// the power a kernel passes of a field sampled `step_cells` lattice cells apart:
// sum_ij k_i k_j rho((i - j) step) = sum_m rho(m step) sum_i k_i k_{i+m}, over the lags m the
// lattice correlates (|m step| < 2)   (k centred at its middle, half-width half). The normalised
// field correlates a little more than the tent (0.285 against 0.25 a cell apart): the diffuse
// mean comes out ~5 % (0.2 dB) high at the defaults; the axial step is taken at c0
double passed_power(const float* k, int half, double step_cells) {
  const int lags = std::min(2 * half, static_cast<int>(std::ceil(2.0 / step_cells)));
  double p = 0.0;
  for (int m = -lags; m <= lags; ++m) {
    const double rho = lattice_correlation(m * step_cells);
    if (rho == 0.0) continue;
    double ac = 0.0;
    for (int i = std::max(-half, -half - m); i <= std::min(half, half - m); ++i) ac += k[i] * k[i + m];
    p += rho * ac;
  }
  return p;
}

// Gaussian taps exp(-k^2 / (2 sigma^2)) for |k| <= half (half = ceil(3 sigma), at most
// kMaxKernelHalf), into out[kMaxKernelHalf + k]; returns half
int gaussian_taps(double sigma, float* out) {
  const int half = std::clamp(static_cast<int>(std::ceil(3.0 * sigma)), 0, BModeRenderer::kMaxKernelHalf);
  std::fill(out, out + 2 * BModeRenderer::kMaxKernelHalf + 1, 0.0f);
  for (int k = -half; k <= half; ++k)
    out[BModeRenderer::kMaxKernelHalf + k] =
        sigma > 1e-6 ? static_cast<float>(std::exp(-0.5 * k * k / (sigma * sigma))) : (k == 0 ? 1.0f : 0.0f);
  return half;
}

}  // namespace

// each scanline's start and direction in the probe's frame, the point-spread kernels per row
// and, for a curvilinear probe, each display pixel's beam-space cell: all depend on the depth
// (sizes do not: nothing is allocated here)
void BModeRenderer::build_geometry() {
  const int w = settings_.width_px, h = settings_.height_px;
  const bool curved = settings_.geometry == ProbeGeometry::kCurvilinear;
  const double fan = settings_.fan_angle_deg * std::numbers::pi / 180.0, rc = settings_.radius_of_curvature_mm;
  for (int c = 0; c < w; ++c) {
    const double t = (c + 0.5) / w - 0.5;
    if (curved) {
      // the apex rc behind the face's centre; the line starts on the face
      const Eigen::Vector2d dir(std::sin(t * fan), std::cos(t * fan));
      line_dir_[c] = dir;
      line_start_[c] = Eigen::Vector2d(0.0, -rc) + rc * dir;
    } else {
      line_dir_[c] = Eigen::Vector2d(0.0, 1.0);
      line_start_[c] = Eigen::Vector2d(t * settings_.width_mm, 0.0);
    }
  }
  // the PSF: axial in samples (constant: depth is time), lateral in scanlines at each row's depth
  const double dx_mm = settings_.depth_mm / h;
  constexpr int mid = kMaxKernelHalf;
  // (at most a third of the longest kernel: truncated further it would turn into a box, whose
  // flat top has no middle)
  steep_half_ = gaussian_taps(std::min(std::max(0.25 * pulse_mm_, 0.5 * voxel_mm_) / dx_mm, kMaxKernelHalf / 3.0),
                              steep_kernel_.data());
  axial_half_ =
      gaussian_taps(axial_psf_sigma_mm(settings_.frequency_mhz, settings_.bandwidth) / dx_mm, axial_kernel_.data());
  // the scatterers' scale: the diffuse echo's mean is the tissue's backscatter whatever the PSF
  // and the lattice (along the lattice's axes; a probe turned to them sees a slightly other grain)
  const double cell = settings_.speckle_cell_mm;
  const double axial_power = passed_power(&axial_kernel_[mid], axial_half_, dx_mm / cell);
  for (int r = 0; r < h; ++r) {
    const double d = (r + 0.5) * dx_mm;
    line_spacing_mm_[r] = static_cast<float>(curved ? (rc + d) * fan / w : settings_.width_mm / w);
    float* k = &lateral_kernel_[static_cast<size_t>(r) * (2 * mid + 1)];
    lateral_half_[r] = gaussian_taps(lateral_psf_sigma_mm(settings_, d) / line_spacing_mm_[r], k);
    double sum = 0.0;
    for (int i = -lateral_half_[r]; i <= lateral_half_[r]; ++i) sum += k[mid + i];
    for (int i = -lateral_half_[r]; i <= lateral_half_[r]; ++i) k[mid + i] = static_cast<float>(k[mid + i] / sum);
    const double power = passed_power(&k[mid], lateral_half_[r], line_spacing_mm_[r] / cell);
    scatter_scale_[r] = static_cast<float>(1.0 / std::sqrt(axial_power * power));
  }
  if (!curved) return;
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

// the acoustic properties at a CT point: with a tissue map, the 8 voxels' tissues' properties
// blended trilinearly (a boundary between voxel centres is a ramp over a voxel, as the HU's);
// without one, the trilinear HU's. Outside the volume the nearest edge voxel (no artificial
// boundary)
Acoustics BModeRenderer::sample_acoustics(const Eigen::Vector3d& p_mm) const {
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
  // (inside one tissue, 8 equal corners, the tissue's own numbers exactly: a blend's rounding
  // would make Z differ in its last bits from sample to sample, and every sample a boundary)
  if (labels_) {
    const int16_t* label = labels_->hu_i16.data();
    int16_t corners[8];
    bool uniform = true;
    for (int corner = 0; corner < 8; ++corner) {
      const int x = corner & 1, y = corner >> 1 & 1, z = corner >> 2 & 1;
      corners[corner] = label[labels_->linear_index(x ? i1[0] : i0[0], y ? i1[1] : i0[1], z ? i1[2] : i0[2])];
      uniform = uniform && corners[corner] == corners[0];
    }
    if (uniform) return label_acoustics_[corners[0]];
    // blended as corner 0's numbers plus the weighted differences: a number the corners share
    // (cortex and medulla have one Z) stays exact across their boundary
    const Acoustics& a0 = label_acoustics_[corners[0]];
    Acoustics out = a0;
    for (int corner = 1; corner < 8; ++corner) {
      const int x = corner & 1, y = corner >> 1 & 1, z = corner >> 2 & 1;
      const auto w = static_cast<float>((x ? f[0] : 1 - f[0]) * (y ? f[1] : 1 - f[1]) * (z ? f[2] : 1 - f[2]));
      const Acoustics& a = label_acoustics_[corners[corner]];
      out.impedance_mrayl += w * (a.impedance_mrayl - a0.impedance_mrayl);
      out.path_ratio += w * (a.path_ratio - a0.path_ratio);
      out.attenuation_factor += w * (a.attenuation_factor - a0.attenuation_factor);
      out.scatter_amplitude += w * (a.scatter_amplitude - a0.scatter_amplitude);
    }
    return out;
  }
  auto v = [&](int64_t i, int64_t j, int64_t k) { return static_cast<double>(ct_.hu(i, j, k)); };
  const double h000 = v(i0[0], i0[1], i0[2]);
  if (h000 == v(i1[0], i0[1], i0[2]) && h000 == v(i0[0], i1[1], i0[2]) && h000 == v(i1[0], i1[1], i0[2]) &&
      h000 == v(i0[0], i0[1], i1[2]) && h000 == v(i1[0], i0[1], i1[2]) && h000 == v(i0[0], i1[1], i1[2]) &&
      h000 == v(i1[0], i1[1], i1[2]))
    return acoustics_of_hu(h000);
  const double c00 = v(i0[0], i0[1], i0[2]) * (1 - f[0]) + v(i1[0], i0[1], i0[2]) * f[0];
  const double c10 = v(i0[0], i1[1], i0[2]) * (1 - f[0]) + v(i1[0], i1[1], i0[2]) * f[0];
  const double c01 = v(i0[0], i0[1], i1[2]) * (1 - f[0]) + v(i1[0], i0[1], i1[2]) * f[0];
  const double c11 = v(i0[0], i1[1], i1[2]) * (1 - f[0]) + v(i1[0], i1[1], i1[2]) * f[0];
  const double c0 = c00 * (1 - f[1]) + c10 * f[1], c1 = c01 * (1 - f[1]) + c11 * f[1];
  return acoustics_of_hu(c0 * (1 - f[2]) + c1 * f[2]);
}

const BModeImage& BModeRenderer::render(const ProbePose& pose, uint64_t seed, const TetSnapshot* deformed) {
  validate(pose);
  const bool mapped = deformed != nullptr;
  if (mapped) {
    if (!have_mesh_) set_mesh(*deformed);
    locator_.refit(*deformed);
  }
  const int w = settings_.width_px, h = settings_.height_px;
  // the passes, each over the pool: the echo needs every scanline's impedance (the boundary's
  // direction across scanlines), the lateral PSF every scanline's axial result
  auto march = [&](int c) { march_scanline(c, pose, seed, mapped); };
  auto echo = [&](int c) {
    echo_scanline(c);
    convolve_axial(c);
  };
  auto lateral = [&](int r) { convolve_lateral(r); };
  pool_.for_each_row(w, march);
  pool_.for_each_row(w, echo);
  pool_.for_each_row(h, lateral);
  if (settings_.geometry == ProbeGeometry::kLinear) return beam_;
  scan_convert();
  return image_;
}

// One scanline in time: screen sample j (depth d_j = (j + 1/2) dx, dx = depth / height) lies
// s_j along the ray, s_0 = dx / 2, s_{j+1} = s_j + dx c_j / c0 (the pulse covers more tissue
// per screen sample where sound is faster: a boundary behind fat, 1450 m/s, shows deeper than it
// is: 20 mm of fat at 21.24 mm). Each sample: its rest point through the tets, the acoustic
// properties there, and the tissue's scatterer in its cell of the undeformed CT.
void BModeRenderer::march_scanline(int column, const ProbePose& pose, uint64_t seed, bool mapped) {
  const int h = settings_.height_px;
  const double dx_mm = settings_.depth_mm / h;
  const Eigen::Vector3d b = pose.beam.normalized();
  const Eigen::Vector3d l = (pose.lateral - pose.lateral.dot(b) * b).normalized();
  const Eigen::Vector3d start = pose.origin_mm + line_start_[column].x() * l + line_start_[column].y() * b;
  const Eigen::Vector3d dir = line_dir_[column].x() * l + line_dir_[column].y() * b;
  const size_t base = static_cast<size_t>(column) * h;
  double s = 0.5 * dx_mm;
  ScattererCell cell;
  int tet = -1;
  for (int j = 0; j < h; ++j) {
    const size_t n = base + j;
    const Eigen::Vector3d p = start + s * dir;
    Eigen::Vector3d q = p;
    if (mapped && !locator_.to_rest(p, &q, &tet)) q = p;
    const Acoustics a = sample_acoustics(q);
    z_[n] = a.impedance_mrayl;
    path_ratio_[n] = a.path_ratio;
    attenuation_[n] = a.attenuation_factor;
    scatter_amplitude_[n] = a.scatter_amplitude;
    const double u[3] = {q.x() / settings_.speckle_cell_mm, q.y() / settings_.speckle_cell_mm,
                         q.z() / settings_.speckle_cell_mm};
    scatterer_[n] = scatterer_field(seed, u, &cell);
    s += dx_mm * path_ratio_[n];
  }
}

// The echo field along one scanline, before the PSF (amplitudes; samples j, path step ds_j):
//   r_j = (Z(j + p/2) - Z(j - p/2)) / (Z(j + p/2) + Z(j - p/2))   specular amplitude
//         reflection, the impedance's change across the pulse p (p / dx screen samples), at the
//         sample where Z changes most steeply (|g_j| a local maximum, g the central difference
//         smoothed over a quarter pulse or half a voxel), none elsewhere: a boundary the CT blurs over a voxel
//         or two echoes as the sharp line it is (a ramp of small steps, each its own echo, came
//         out 6 dB weak under a PSF narrower than the ramp)
//   cos^2 theta_j = g_a^2 / (g_a^2 + g_l^2)                 g: Z's gradient in the image plane,
//         along the beam and across scanlines: the boundary's normal against the beam (1 where
//         the gradient vanishes)
//   e_j = A_j (r_j cos^(n/2) theta_j + k_j sqrt(sigma_j) a_j)   a_j the tissue's scatterer,
//         k_j the row's scatter scale, n the specular exponent (intensity ~ cos^n)
//   A_j = T_j 10^(-L_j / 10)                                round trip: sqrt(T^2 10^(-2 L / 10))
//   R_j = ((Z(s_j + p/2) - Z(s_j - p/2)) / (Z(s_j + p/2) + Z(s_j - p/2)))^2   over the pulse p
//   T_{j+1} = T_j (1 - R_j)^(dx / p)                         one-way transmission (shadowing)
//   L_j = sum_{i<j} a_i ds_i + a_j ds_j / 2,  a_i = alpha_i f    one-way loss, dB
// [Goksel & Salcudean 2009: reflection + scattering, attenuated; Buerger et al. 2013: the
// specular echo's fall-off with the angle of incidence]
void BModeRenderer::echo_scanline(int column) {
  const int h = settings_.height_px, w = settings_.width_px;
  const double dx_mm = settings_.depth_mm / h;
  const double half = 0.5 * pulse_mm_ / dx_mm;  // half window in samples
  const size_t base = static_cast<size_t>(column) * h;
  const float* z = &z_[base];
  // the neighbouring scanlines' impedance, for the gradient across them (one-sided at the edges)
  // Z's gradient over half a CT voxel either side (at least a sample): over less, the direction
  // follows the trilinear field's kinks at the voxels' faces and a sloping boundary echoes in
  // short level dashes
  const int along = std::max(1, static_cast<int>(std::lround(0.5 * voxel_mm_ / dx_mm)));
  auto z_at = [&](double s) {
    s = std::clamp(s, 0.0, static_cast<double>(h - 1));
    const int i = std::min(static_cast<int>(s), h - 2);
    const double f = s - i;
    return z[i] * (1 - f) + z[i + 1] * f;
  };
  // where Z changes most steeply: |g_j| a local maximum, g the central difference Z_{j+1} -
  // Z_{j-1} smoothed by a Gaussian of a quarter pulse or half a CT voxel, the longer (a ramp then peaks at its middle,
  // not anywhere along a flat top)
  float* steep = &steepness_[base];
  const float* g = &steep_kernel_[kMaxKernelHalf];
  // (where Z is flat across the whole window, as inside one tissue, the sum is 0: skipped; the
  // window's last change is tracked from its upper end)
  int last_change = -1000000;
  for (int j = -steep_half_; j < h; ++j) {
    const int top = std::clamp(j + steep_half_, 1, h - 2);
    if (z[top + 1] != z[top - 1]) last_change = j + steep_half_;
    if (j < 0) continue;
    if (last_change < j - steep_half_) {
      steep[j] = 0.0f;
      continue;
    }
    float sum = 0.0f;
    for (int i = -steep_half_; i <= steep_half_; ++i) {
      const int m = std::clamp(j + i, 1, h - 2);
      sum += g[i] * (z[m + 1] - z[m - 1]);
    }
    steep[j] = sum;
  }
  const double step_exponent = dx_mm / pulse_mm_;
  const double quarter_n = 0.25 * settings_.specular_exponent;
  const double db_to_ln = std::numbers::ln10 / 10.0;
  // the loss as a running product, 10^(-L_j / 10) = prod_{i<j} 10^(-a_i / 10) (each step's factor
  // taken again only where the tissue changes)
  double transmitted = 1.0, passed = 1.0, last_a_db = -1.0, half_step = 1.0;
  for (int j = 0; j < h; ++j) {
    const double ds_cm = dx_mm * path_ratio_[base + j] / 10.0;
    const double a_db =
        attenuation_db(settings_.attenuation_db_per_cm_mhz, attenuation_[base + j], settings_.frequency_mhz, ds_cm);
    if (a_db != last_a_db) {
      last_a_db = a_db;
      half_step = std::exp(-0.5 * a_db * db_to_ln);
    }
    const double amplitude = transmitted * passed * half_step;
    double specular = 0.0;
    const float here = std::abs(steep[j]);
    if (j > 0 && j + 1 < h && here > 0.0f && here > std::abs(steep[j - 1]) && here >= std::abs(steep[j + 1])) {
      const double z1 = z_at(j - half), z2 = z_at(j + half);
      specular = (z2 - z1) / (z2 + z1);
      const int a0 = std::max(j - along, 0), a1 = std::min(j + along, h - 1);
      const double g_a = (z[a1] - z[a0]) / ((a1 - a0) * dx_mm * path_ratio_[base + j]);
      const int m = std::max(1, static_cast<int>(std::lround(0.5 * voxel_mm_ / line_spacing_mm_[j])));
      const int left = std::max(column - m, 0), right = std::min(column + m, w - 1);
      const double g_l = (z_[static_cast<size_t>(right) * h + j] - z_[static_cast<size_t>(left) * h + j]) /
                         (std::max(right - left, 1) * line_spacing_mm_[j]);
      // (a thin layer's middle: Z the same either side, no direction; the echo is square on)
      const double g2 = g_a * g_a + g_l * g_l;
      const double cos2 = g2 > 0.0 ? g_a * g_a / g2 : 1.0;
      if (quarter_n > 0.0) specular *= std::exp(quarter_n * std::log(std::max(cos2, 1e-300)));
    }
    const double diffuse = scatter_scale_[j] * scatter_amplitude_[base + j];
    field_[base + j] = static_cast<float>(amplitude) *
                       (static_cast<float>(specular) + static_cast<float>(diffuse) * scatterer_[base + j]);
    // (within one tissue the window's ends are equal: nothing reflected, nothing to take)
    const double refl = reflection(z_at(j - half), z_at(j + half));
    if (refl > 0.0) transmitted *= std::exp(step_exponent * std::log1p(-std::min(refl, 1.0 - 1e-12)));
    passed *= half_step * half_step;
  }
}

// the axial PSF along one scanline (the field clamped at its ends), into row-major order
void BModeRenderer::convolve_axial(int column) {
  const int h = settings_.height_px, w = settings_.width_px;
  const std::complex<float>* f = &field_[static_cast<size_t>(column) * h];
  const float* k = &axial_kernel_[kMaxKernelHalf];
  for (int j = 0; j < h; ++j) {
    std::complex<float> sum = 0.0f;
    for (int i = -axial_half_; i <= axial_half_; ++i) sum += k[i] * f[std::clamp(j + i, 0, h - 1)];
    axial_[static_cast<size_t>(j) * w + column] = sum;
  }
}

// the lateral PSF across one row (clamped at the image's sides), the envelope squared, then
// TGC, gain and log compression:  I = |e|^2,  B = 10 log10 I + gain + tgc d_cm
void BModeRenderer::convolve_lateral(int row) {
  const int w = settings_.width_px;
  const std::complex<float>* a = &axial_[static_cast<size_t>(row) * w];
  const float* k = &lateral_kernel_[static_cast<size_t>(row) * (2 * kMaxKernelHalf + 1) + kMaxKernelHalf];
  const int half = lateral_half_[row];
  const double depth_cm = (row + 0.5) * settings_.depth_mm / settings_.height_px / 10.0;
  for (int c = 0; c < w; ++c) {
    std::complex<float> sum = 0.0f;
    for (int i = -half; i <= half; ++i) sum += k[i] * a[std::clamp(c + i, 0, w - 1)];
    const size_t out = static_cast<size_t>(row) * w + c;
    echo_[out] = std::norm(sum);
    beam_.pixels[out] = log_compress(brightness_db(echo_[out], settings_.gain_db, settings_.tgc_db_per_cm, depth_cm),
                                     settings_.dynamic_range_db);
  }
}

}  // namespace pcisim::ultrasound
