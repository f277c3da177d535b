#pragma once
// The B-mode renderer's passes, one scanline, sample or pixel each, written once for the CPU
// renderer (bmode_renderer.cc, over its row pool) and its CUDA twin (cuda_bmode.cu, one GPU
// thread each): the same arithmetic on the same arrays, host or device. bmode_renderer.h
// describes the image formation; the equations are above each pass.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "ultrasound/echo/echo_rules.h"
#include "ultrasound/echo/tissue_acoustics.h"
#include "ultrasound/mapping/tet_lookup.h"

namespace pcisim::ultrasound::kernels {

constexpr int kMaxKernelHalf = 64;  // the point-spread kernels' largest half-width

// a frame's arrays and settings. Per sample (column-major, scanline by scanline): impedance, the
// path's step c / c0, the attenuation factor, the scatterers' amplitude, the scatterer, Z's
// smoothed change, the echo field; row-major: the field after the axial PSF, the intensity, the
// beam-space grey levels; per display pixel (curvilinear) the beam-space cell and its weights
struct FrameView {
  int width = 0, height = 0;
  double dx_mm = 0, depth_mm = 0, pulse_mm = 0, voxel_mm = 0, speckle_cell_mm = 0;
  double attenuation_db_per_cm_mhz = 0, frequency_mhz = 0, specular_exponent = 0;
  double gain_db = 0, tgc_db_per_cm = 0, dynamic_range_db = 0;
  const double* line_start = nullptr;  // 2 per scanline: lateral, along the beam (mm)
  const double* line_dir = nullptr;
  float *z = nullptr, *path_ratio = nullptr, *attenuation = nullptr, *scatter_amplitude = nullptr;
  Cf *scatterer = nullptr, *field = nullptr, *axial = nullptr;
  float *steepness = nullptr, *echo = nullptr;
  // the GPU's split of the march and the echo (null on the CPU): per sample the rest point in
  // scatterer cells (3), the half-step loss factor, the transmission factor, the amplitude A_j
  double *rest_cells = nullptr, *half_step = nullptr, *transmission = nullptr, *amplitude = nullptr;
  uint8_t *beam = nullptr, *image = nullptr;
  const float *axial_kernel = nullptr, *steep_kernel = nullptr;  // 2 kMaxKernelHalf + 1 taps
  const float* lateral_kernel = nullptr;                         // as many taps per row
  const float *line_spacing_mm = nullptr, *scatter_scale = nullptr;
  const int* lateral_half = nullptr;
  int axial_half = 0, steep_half = 0;
  const int* convert_index = nullptr;
  const float *convert_fx = nullptr, *convert_fy = nullptr;
};

// the probe this frame: the face's centre, the lateral and beam unit vectors (CT, mm)
struct PoseView {
  double origin[3], lateral[3], beam[3];
};

// a tissue map on the CT's grid: labels and each label's acoustic properties; the world-to-index
// map (row-major 3 x 3 applied to p - origin)
struct LabelView {
  int64_t dims[3] = {0, 0, 0};
  double origin[3] = {0, 0, 0};
  double world_to_index[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const int16_t* labels = nullptr;
  const Acoustics* acoustics = nullptr;
};

// the acoustic properties at a CT point from the tissue map: the 8 voxels' tissues' properties
// blended trilinearly (a boundary between voxel centres is a ramp over a voxel); outside the
// volume the nearest edge voxel (no artificial boundary)
PCISIM_HD inline Acoustics sample_labels(const LabelView& v, const double (&p)[3]) {
  const double d[3] = {p[0] - v.origin[0], p[1] - v.origin[1], p[2] - v.origin[2]};
  int64_t i0[3], i1[3];
  double f[3];
  for (int k = 0; k < 3; ++k) {
    const double* m = v.world_to_index + 3 * k;
    const double u = m[0] * d[0] + m[1] * d[1] + m[2] * d[2];
    const double x = std::clamp(u, 0.0, static_cast<double>(v.dims[k] - 1));
    i0[k] = std::min<int64_t>(static_cast<int64_t>(x), std::max<int64_t>(v.dims[k] - 2, 0));
    f[k] = x - static_cast<double>(i0[k]);
    i1[k] = std::min<int64_t>(i0[k] + 1, v.dims[k] - 1);
  }
  // (inside one tissue, 8 equal corners, the tissue's own numbers exactly: a blend's rounding
  // would make Z differ in its last bits from sample to sample, and every sample a boundary)
  int16_t corners[8];
  bool uniform = true;
  for (int corner = 0; corner < 8; ++corner) {
    const int x = corner & 1, y = corner >> 1 & 1, z = corner >> 2 & 1;
    corners[corner] =
        v.labels[(x ? i1[0] : i0[0]) + v.dims[0] * ((y ? i1[1] : i0[1]) + v.dims[1] * (z ? i1[2] : i0[2]))];
    uniform = uniform && corners[corner] == corners[0];
  }
  if (uniform) return v.acoustics[corners[0]];
  // blended as corner 0's numbers plus the weighted differences: a number the corners share
  // (cortex and medulla have one Z) stays exact across their boundary
  const Acoustics& a0 = v.acoustics[corners[0]];
  Acoustics out = a0;
  for (int corner = 1; corner < 8; ++corner) {
    const int x = corner & 1, y = corner >> 1 & 1, z = corner >> 2 & 1;
    const auto w = static_cast<float>((x ? f[0] : 1 - f[0]) * (y ? f[1] : 1 - f[1]) * (z ? f[2] : 1 - f[2]));
    const Acoustics& a = v.acoustics[corners[corner]];
    out.impedance_mrayl += w * (a.impedance_mrayl - a0.impedance_mrayl);
    out.path_ratio += w * (a.path_ratio - a0.path_ratio);
    out.attenuation_factor += w * (a.attenuation_factor - a0.attenuation_factor);
    out.scatter_amplitude += w * (a.scatter_amplitude - a0.scatter_amplitude);
  }
  return out;
}

// One scanline in time: screen sample j (depth d_j = (j + 1/2) dx, dx = depth / height) lies
// s_j along the ray, s_0 = dx / 2, s_{j+1} = s_j + dx c_j / c0 (the pulse covers more tissue
// per screen sample where sound is faster: a boundary behind fat, 1450 m/s, shows deeper than it
// is: 20 mm of fat at 21.24 mm). Each sample: its rest point through the tets (locator null: the
// CT undeformed), the acoustic properties there (sample(q): the tissue map's or the HU's), and
// the tissue's scatterer in its cell of the undeformed CT (table: kScatterers amplitudes;
// mixed_seed = splitmix64(seed)). With f.rest_cells the rest point in lattice cells is kept
// instead, for scatter_sample (the GPU: the march is one thread a scanline, the scatterers one a
// sample)
template <class Sample>
PCISIM_HD void march_scanline(const FrameView& f, const PoseView& pose, const LocatorView* locator, const Cf* table,
                              uint64_t mixed_seed, const Sample& sample, int column) {
  const int h = f.height;
  const double* ls = f.line_start + 2 * column;
  const double* ld = f.line_dir + 2 * column;
  double start[3], dir[3];
  for (int k = 0; k < 3; ++k) {
    start[k] = pose.origin[k] + ls[0] * pose.lateral[k] + ls[1] * pose.beam[k];
    dir[k] = ld[0] * pose.lateral[k] + ld[1] * pose.beam[k];
  }
  const int64_t base = static_cast<int64_t>(column) * h;
  double s = 0.5 * f.dx_mm;
  ScattererCell cell;
  int tet = -1;
  for (int j = 0; j < h; ++j) {
    const int64_t n = base + j;
    const double p[3] = {start[0] + s * dir[0], start[1] + s * dir[1], start[2] + s * dir[2]};
    double q[3] = {p[0], p[1], p[2]};
    if (locator && !rest_point(*locator, p, q, &tet)) q[0] = p[0], q[1] = p[1], q[2] = p[2];
    const Acoustics a = sample(q);
    f.z[n] = a.impedance_mrayl;
    f.path_ratio[n] = a.path_ratio;
    f.attenuation[n] = a.attenuation_factor;
    f.scatter_amplitude[n] = a.scatter_amplitude;
    const double u[3] = {q[0] / f.speckle_cell_mm, q[1] / f.speckle_cell_mm, q[2] / f.speckle_cell_mm};
    if (f.rest_cells) {
      for (int k = 0; k < 3; ++k) f.rest_cells[3 * n + k] = u[k];
    } else {
      f.scatterer[n] = scatterer_field(table, mixed_seed, u, &cell);
    }
    s += f.dx_mm * f.path_ratio[n];
  }
}

// sample n's scatterer from its kept rest point (march_scanline with f.rest_cells): the cached
// field's value bit for bit
PCISIM_HD inline void scatter_sample(const FrameView& f, const Cf* table, uint64_t mixed_seed, int64_t n) {
  const double u[3] = {f.rest_cells[3 * n], f.rest_cells[3 * n + 1], f.rest_cells[3 * n + 2]};
  ScattererCell cell;
  f.scatterer[n] = scatterer_field(table, mixed_seed, u, &cell);
}

// Z along one scanline at fractional sample s (linear between samples, clamped at the ends)
PCISIM_HD inline double z_along(const FrameView& f, int column, double s) {
  const int h = f.height;
  const float* z = f.z + static_cast<int64_t>(column) * h;
  s = std::clamp(s, 0.0, static_cast<double>(h - 1));
  const int i = std::min(static_cast<int>(s), h - 2);
  const double t = s - i;
  return z[i] * (1 - t) + z[i + 1] * t;
}

// The echo field along one scanline, before the PSF (amplitudes; samples j, path step ds_j):
//   r_j = (Z(j + p/2) - Z(j - p/2)) / (Z(j + p/2) + Z(j - p/2))   specular amplitude
//         reflection, the impedance's change across the pulse p (p / dx screen samples), at the
//         sample where Z changes most steeply (|g_j| a local maximum, g the central difference
//         smoothed over a quarter pulse or half a voxel), none elsewhere: a boundary the CT
//         blurs over a voxel or two echoes as the sharp line it is (a ramp of small steps, each
//         its own echo, came out 6 dB weak under a PSF narrower than the ramp)
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
// specular echo's fall-off with the angle of incidence]. One rule per function below;
// echo_scanline puts them together along a scanline (the CPU), the GPU runs each over all samples
// and only the running products A_j one thread a scanline (amplitude_scanline).

// g_j: the central difference Z_{j+1} - Z_{j-1} smoothed by a Gaussian of a quarter pulse or
// half a CT voxel, the longer (a ramp then peaks at its middle, not anywhere along a flat top);
// exactly 0 where Z is flat across the window
PCISIM_HD inline float steepness_sample(const FrameView& f, int column, int j) {
  const int h = f.height;
  const float* z = f.z + static_cast<int64_t>(column) * h;
  const float* g = f.steep_kernel + kMaxKernelHalf;
  float sum = 0.0f;
  for (int i = -f.steep_half; i <= f.steep_half; ++i) {
    const int m = std::clamp(j + i, 1, h - 2);
    sum += g[i] * (z[m + 1] - z[m - 1]);
  }
  return sum;
}

// a_j ds_j: the one-way loss (dB) over sample n's path step
PCISIM_HD inline double loss_db(const FrameView& f, int64_t n) {
  const double ds_cm = f.dx_mm * f.path_ratio[n] / 10.0;
  return attenuation_db(f.attenuation_db_per_cm_mhz, f.attenuation[n], f.frequency_mhz, ds_cm);
}

// 10^(-a ds / 20): the amplitude over half a step's loss (its square the whole step's intensity)
PCISIM_HD inline double half_step_factor(double loss_db) {
  return std::exp(-0.5 * loss_db * (2.302585092994045684 / 10.0));  // ln 10 / 10
}

// (1 - R_j)^(dx / p): the transmission across sample j's step (1 within one tissue, where the
// window's ends are equal)
PCISIM_HD inline double transmission_factor(const FrameView& f, int column, int j) {
  const double half = 0.5 * f.pulse_mm / f.dx_mm;  // half window in samples
  const double refl = reflection(z_along(f, column, j - half), z_along(f, column, j + half));
  if (!(refl > 0.0)) return 1.0;
  return std::exp(f.dx_mm / f.pulse_mm * std::log1p(-std::min(refl, 1.0 - 1e-12)));
}

// r_j cos^(n/2) theta_j at a local maximum of |g| (f.steepness filled for the scanline), else 0
PCISIM_HD inline double specular_echo(const FrameView& f, int column, int j) {
  const int h = f.height, w = f.width;
  const int64_t base = static_cast<int64_t>(column) * h;
  const float* steep = f.steepness + base;
  const float here = std::fabs(steep[j]);
  if (!(j > 0 && j + 1 < h && here > 0.0f && here > std::fabs(steep[j - 1]) && here >= std::fabs(steep[j + 1])))
    return 0.0;
  const double dx_mm = f.dx_mm;
  const double half = 0.5 * f.pulse_mm / dx_mm;
  const double z1 = z_along(f, column, j - half), z2 = z_along(f, column, j + half);
  double specular = (z2 - z1) / (z2 + z1);
  // Z's gradient over half a CT voxel either side (at least a sample): over less, the direction
  // follows the trilinear field's kinks at the voxels' faces and a sloping boundary echoes in
  // short level dashes
  const float* z = f.z + base;
  const int along = std::max(1, static_cast<int>(std::floor(0.5 * f.voxel_mm / dx_mm + 0.5)));
  const int a0 = std::max(j - along, 0), a1 = std::min(j + along, h - 1);
  const double g_a = (z[a1] - z[a0]) / ((a1 - a0) * dx_mm * f.path_ratio[base + j]);
  const int m = std::max(1, static_cast<int>(std::floor(0.5 * f.voxel_mm / f.line_spacing_mm[j] + 0.5)));
  const int left = std::max(column - m, 0), right = std::min(column + m, w - 1);
  const double g_l = (f.z[static_cast<int64_t>(right) * h + j] - f.z[static_cast<int64_t>(left) * h + j]) /
                     (std::max(right - left, 1) * f.line_spacing_mm[j]);
  // (a thin layer's middle: Z the same either side, no direction; the echo is square on)
  const double g2 = g_a * g_a + g_l * g_l;
  const double cos2 = g2 > 0.0 ? g_a * g_a / g2 : 1.0;
  const double quarter_n = 0.25 * f.specular_exponent;
  if (quarter_n > 0.0) specular *= std::exp(quarter_n * std::log(std::max(cos2, 1e-300)));
  return specular;
}

// e_j = A_j (r_j cos^(n/2) theta_j + k_j sqrt(sigma_j) a_j) at sample j of a scanline
PCISIM_HD inline Cf echo_field(const FrameView& f, int column, int j, double amplitude) {
  const int64_t n = static_cast<int64_t>(column) * f.height + j;
  const double diffuse = f.scatter_scale[j] * f.scatter_amplitude[n];
  const Cf a = f.scatterer[n];
  const auto amp = static_cast<float>(amplitude), spec = static_cast<float>(specular_echo(f, column, j));
  const auto diff = static_cast<float>(diffuse);
  return {amp * (spec + diff * a.re), amp * (diff * a.im)};
}

// A_j along one scanline from each sample's half-step and transmission factors (f.half_step,
// f.transmission), into f.amplitude: T and the loss as running products, in the order
// echo_scanline takes them
PCISIM_HD inline void amplitude_scanline(const FrameView& f, int column) {
  const int64_t base = static_cast<int64_t>(column) * f.height;
  double transmitted = 1.0, passed = 1.0;
  for (int j = 0; j < f.height; ++j) {
    const double half_step = f.half_step[base + j];
    f.amplitude[base + j] = transmitted * passed * half_step;
    transmitted *= f.transmission[base + j];
    passed *= half_step * half_step;
  }
}

// the echo field along one scanline on one thread (the CPU): needs every scanline's Z (the
// boundary's direction across scanlines). Where Z is flat across the whole smoothing window, as
// inside one tissue, g is 0 and not summed (the window's last change tracked from its upper end);
// each step's loss factor is taken again only where the tissue changes
PCISIM_HD inline void echo_scanline(const FrameView& f, int column) {
  const int h = f.height;
  const int64_t base = static_cast<int64_t>(column) * h;
  const float* z = f.z + base;
  float* steep = f.steepness + base;
  const int sh = f.steep_half;
  int last_change = -1000000;
  for (int j = -sh; j < h; ++j) {
    const int top = std::clamp(j + sh, 1, h - 2);
    if (z[top + 1] != z[top - 1]) last_change = j + sh;
    if (j < 0) continue;
    steep[j] = last_change < j - sh ? 0.0f : steepness_sample(f, column, j);
  }
  double transmitted = 1.0, passed = 1.0, last_loss = -1.0, half_step = 1.0;
  for (int j = 0; j < h; ++j) {
    const double loss = loss_db(f, base + j);
    if (loss != last_loss) {
      last_loss = loss;
      half_step = half_step_factor(loss);
    }
    f.field[base + j] = echo_field(f, column, j, transmitted * passed * half_step);
    transmitted *= transmission_factor(f, column, j);
    passed *= half_step * half_step;
  }
}

// the axial PSF at sample j of one scanline (the field clamped at its ends), into row-major order
PCISIM_HD inline void axial_sample(const FrameView& f, int column, int j) {
  const int h = f.height;
  const Cf* in = f.field + static_cast<int64_t>(column) * h;
  const float* k = f.axial_kernel + kMaxKernelHalf;
  float re = 0.0f, im = 0.0f;
  for (int i = -f.axial_half; i <= f.axial_half; ++i) {
    const Cf v = in[std::clamp(j + i, 0, h - 1)];
    re += k[i] * v.re;
    im += k[i] * v.im;
  }
  f.axial[static_cast<int64_t>(j) * f.width + column] = {re, im};
}

// the lateral PSF at one pixel (clamped at the image's sides), the envelope squared, then TGC,
// gain and log compression:  I = |e|^2,  B = 10 log10 I + gain + tgc d_cm
PCISIM_HD inline void lateral_pixel(const FrameView& f, int row, int c) {
  const int w = f.width;
  const Cf* a = f.axial + static_cast<int64_t>(row) * w;
  const float* k = f.lateral_kernel + static_cast<int64_t>(row) * (2 * kMaxKernelHalf + 1) + kMaxKernelHalf;
  const int half = f.lateral_half[row];
  const double depth_cm = (row + 0.5) * f.depth_mm / f.height / 10.0;
  float re = 0.0f, im = 0.0f;
  for (int i = -half; i <= half; ++i) {
    const Cf v = a[std::clamp(c + i, 0, w - 1)];
    re += k[i] * v.re;
    im += k[i] * v.im;
  }
  const int64_t out = static_cast<int64_t>(row) * w + c;
  f.echo[out] = re * re + im * im;
  f.beam[out] = log_compress(brightness_db(f.echo[out], f.gain_db, f.tgc_db_per_cm, depth_cm), f.dynamic_range_db);
}

// curvilinear display pixel k: bilinear in the beam-space grey levels, black outside the fan
PCISIM_HD inline void scan_convert_pixel(const FrameView& f, int64_t k) {
  const int i = f.convert_index[k];
  if (i < 0) {
    f.image[k] = 0;
    return;
  }
  const float fx = f.convert_fx[k], fy = f.convert_fy[k];
  const uint8_t* p = f.beam + i;
  const int w = f.width;
  const float v = (p[0] * (1 - fx) + p[1] * fx) * (1 - fy) + (p[w] * (1 - fx) + p[w + 1] * fx) * fy;
  f.image[k] = static_cast<uint8_t>(std::floor(v + 0.5f));
}

}  // namespace pcisim::ultrasound::kernels
