#include "ultrasound/render/bmode_renderer.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#ifdef PCISIM_US_HAVE_PNG
#include "png/png_gray.h"
#endif
#include "ultrasound/echo/acoustic_model.h"
#include "ultrasound/echo/point_spread.h"

namespace pcisim::ultrasound {
void write_png(const std::string& path, const BModeImage& image) {
#ifdef PCISIM_US_HAVE_PNG
  png::write_png_gray8(path, image.width, image.height, image.pixels.data());
#else
  (void)image;
  throw std::runtime_error(path + ": this build has no libpng (the ultrasound frame is not written)");
#endif
}

BModeRenderer::BModeRenderer(const anatomy::Volume& ct, const UsSettings& settings, const anatomy::TissueMap* tissue)
    // (the GPU's frames use no CPU threads: the pool is the caller alone)
    : ct_(ct),
      settings_(settings),
      pool_((validate(settings), settings.renderer == UsRenderer::kCuda ? 1 : settings.threads)) {
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
  if (labels_) {
    for (int k = 0; k < 3; ++k) {
      label_view_.dims[k] = labels_->dims[k];
      label_view_.origin[k] = ct_.origin_mm[k];  // (the map's may differ by 1e-3 voxel: the CT's grid is used)
      for (int c = 0; c < 3; ++c) label_view_.world_to_index[3 * k + c] = world_to_index_(k, c);
    }
    label_view_.labels = labels_->hu_i16.data();
    label_view_.acoustics = label_acoustics_.data();
  }
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
  if (settings_.renderer == UsRenderer::kCuda) {
#ifdef PCISIM_HAVE_CUDA
    if (!labels_)
      throw std::runtime_error(
          "ultrasound: the cuda renderer needs the case's tissue map (it samples tissues, not HU)");
    if (cuda::device_count() == 0) throw std::runtime_error("ultrasound: the cuda renderer: no CUDA device is visible");
    device_ = std::make_unique<cuda::BModeDevice>(label_view_, static_cast<int64_t>(labels_->hu_i16.size()),
                                                  static_cast<int>(label_acoustics_.size()), settings_.width_px,
                                                  settings_.height_px);
    // (what each frame copies back: echo_ and the images are never resized after this)
    device_->pin(echo_.data(), echo_.size() * sizeof(float));
    device_->pin(beam_.pixels.data(), beam_.pixels.size());
    device_->pin(image_.pixels.data(), image_.pixels.size());
#else
    throw std::runtime_error("ultrasound: the cuda renderer: this build has no CUDA (PCISIM_CUDA)");
#endif
  }
  build_geometry();
}

BModeRenderer::~BModeRenderer() = default;

float BModeRenderer::last_gpu_kernel_ms() const {
#ifdef PCISIM_HAVE_CUDA
  if (device_) return device_->last_kernel_ms();
#endif
  return 0.0f;
}

const std::vector<float>& BModeRenderer::echo_intensity() const {
#ifdef PCISIM_HAVE_CUDA
  if (device_ && echo_on_device_) {
    device_->download_echo(const_cast<float*>(echo_.data()));
    echo_on_device_ = false;
  }
#endif
  return echo_;
}

const float* BModeRenderer::last_gpu_pass_ms() const {
#ifdef PCISIM_HAVE_CUDA
  if (device_) return device_->last_pass_ms();
#endif
  return nullptr;
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
  if (curved) build_scan_conversion();
#ifdef PCISIM_HAVE_CUDA
  if (device_) device_->upload_geometry(frame_view(), curved);
#endif
}

// a curvilinear probe's display: each pixel's beam-space cell and weights
void BModeRenderer::build_scan_conversion() {
  const int w = settings_.width_px, h = settings_.height_px;
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

void BModeRenderer::set_mesh(const TetSnapshot& mesh) {
  locator_.build(mesh);
  have_mesh_ = true;
#ifdef PCISIM_HAVE_CUDA
  if (device_) device_->upload_rest(locator_.view());
#endif
}

// the acoustic properties at a CT point without a tissue map: the trilinear HU's (a boundary
// between voxel centres is a ramp over a voxel). Outside the volume the nearest edge voxel (no
// artificial boundary). With a map: kernels::sample_labels
Acoustics BModeRenderer::sample_hu(const double (&p_mm)[3]) const {
  const Eigen::Vector3d u = world_to_index_ * (Eigen::Vector3d(p_mm[0], p_mm[1], p_mm[2]) - ct_.origin_mm);
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

kernels::FrameView BModeRenderer::frame_view() {
  kernels::FrameView f;
  f.width = settings_.width_px;
  f.height = settings_.height_px;
  f.dx_mm = settings_.depth_mm / settings_.height_px;
  f.depth_mm = settings_.depth_mm;
  f.pulse_mm = pulse_mm_;
  f.voxel_mm = voxel_mm_;
  f.speckle_cell_mm = settings_.speckle_cell_mm;
  f.attenuation_db_per_cm_mhz = settings_.attenuation_db_per_cm_mhz;
  f.frequency_mhz = settings_.frequency_mhz;
  f.specular_exponent = settings_.specular_exponent;
  f.gain_db = settings_.gain_db;
  f.tgc_db_per_cm = settings_.tgc_db_per_cm;
  f.dynamic_range_db = settings_.dynamic_range_db;
  f.line_start = line_start_[0].data();
  f.line_dir = line_dir_[0].data();
  f.z = z_.data();
  f.path_ratio = path_ratio_.data();
  f.attenuation = attenuation_.data();
  f.scatter_amplitude = scatter_amplitude_.data();
  f.scatterer = scatterer_.data();
  f.field = field_.data();
  f.axial = axial_.data();
  f.steepness = steepness_.data();
  f.echo = echo_.data();
  f.beam = beam_.pixels.data();
  f.image = image_.pixels.data();
  f.axial_kernel = axial_kernel_.data();
  f.steep_kernel = steep_kernel_.data();
  f.lateral_kernel = lateral_kernel_.data();
  f.line_spacing_mm = line_spacing_mm_.data();
  f.scatter_scale = scatter_scale_.data();
  f.lateral_half = lateral_half_.data();
  f.axial_half = axial_half_;
  f.steep_half = steep_half_;
  f.convert_index = convert_index_.data();
  f.convert_fx = convert_fx_.data();
  f.convert_fy = convert_fy_.data();
  return f;
}

const BModeImage& BModeRenderer::render(const ProbePose& pose, uint64_t seed, const TetSnapshot* deformed) {
  validate(pose);
  const bool mapped = deformed != nullptr;
  if (mapped) {
    if (!have_mesh_) set_mesh(*deformed);
    locator_.refit(*deformed);
  }
  const int w = settings_.width_px, h = settings_.height_px;
  kernels::PoseView p;
  const Eigen::Vector3d b = pose.beam.normalized();
  const Eigen::Vector3d l = (pose.lateral - pose.lateral.dot(b) * b).normalized();
  for (int k = 0; k < 3; ++k) {
    p.origin[k] = pose.origin_mm[k];
    p.lateral[k] = l[k];
    p.beam[k] = b[k];
  }
  const kernels::FrameView f = frame_view();
  const LocatorView locator = locator_.view();
  const LocatorView* through = mapped ? &locator : nullptr;
  const bool curved = settings_.geometry == ProbeGeometry::kCurvilinear;
#ifdef PCISIM_HAVE_CUDA
  if (device_) {
    device_->render(f, p, through, locator_.cell_count(), locator_.entry_count(), locator_.entries_capacity(),
                    splitmix64(seed), curved);
    echo_on_device_ = true;
    return curved ? image_ : beam_;
  }
#endif
  // the passes, each over the pool: the echo needs every scanline's impedance (the boundary's
  // direction across scanlines), the lateral PSF every scanline's axial result
  const Cf* table = scatterer_table();
  const uint64_t mixed = splitmix64(seed);
  auto march = [&](int c) {
    if (labels_)
      kernels::march_scanline(
          f, p, through, table, mixed, [&](const double(&q)[3]) { return kernels::sample_labels(label_view_, q); }, c);
    else
      kernels::march_scanline(
          f, p, through, table, mixed, [&](const double(&q)[3]) { return sample_hu(q); }, c);
  };
  auto echo = [&](int c) {
    kernels::echo_scanline(f, c);
    for (int j = 0; j < h; ++j) kernels::axial_sample(f, c, j);
  };
  auto lateral = [&](int r) {
    for (int c = 0; c < w; ++c) kernels::lateral_pixel(f, r, c);
  };
  pool_.for_each_row(w, march);
  pool_.for_each_row(w, echo);
  pool_.for_each_row(h, lateral);
  if (!curved) return beam_;
  for (size_t k = 0; k < image_.pixels.size(); ++k) kernels::scan_convert_pixel(f, static_cast<int64_t>(k));
  return image_;
}

}  // namespace pcisim::ultrasound
