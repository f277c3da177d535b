#pragma once
// B-mode ultrasound from the preoperative CT through the deformed tissue (issue #16 item 4,
// issue #32; soft-tissue paper, "Weighted matrix blending"). Each scanline is marched in time:
// a sample's depth on the screen is c0 t / 2, its place along the ray the distance the pulse
// travelled at each tissue's speed of sound. Each sample in the deformed configuration is
// carried to the undeformed CT through the tet holding it (outside every tet the CT is sampled
// where the sample is: the organ's surroundings are undeformed); there the tissue map's tissues
// give impedance, speed, scattering and attenuation (echo/tissue_acoustics.h, the 8 voxels'
// properties blended trilinearly), or without a map the HU (echo/acoustic_model.h); its
// undeformed place gives the tissue's scatterer. The echo field (specular reflection at impedance changes, with its
// fall-off with the angle of incidence, plus the scatterers, attenuated and shadowed along the beam) is convolved with
// the probe's point-spread function (echo/point_spread.h: separable, axial then lateral), its envelope taken, time-gain
// compensated and log-compressed. render() returns the display image (display_pixel_to_world in probe/us_settings.h:
// beam space for a linear probe, the scan-converted fan for a curvilinear one); beam_image() the beam-space one
// (pixel_to_world). The constructor and set_mesh() allocate; render() and set_imaging() allocate
// nothing. The passes are bmode_kernels.h's: on the CPU over settings.threads threads, or, with
// settings.renderer kCuda, on the GPU (cuda_bmode.h; the same kernels, a tissue map needed).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "anatomy/organ/organ.h"
#include "anatomy/volume/volume.h"
#include "realtime/row_pool.h"
#include "ultrasound/echo/tissue_acoustics.h"
#include "ultrasound/mapping/tet_locator.h"
#include "ultrasound/mapping/tet_snapshot.h"
#include "ultrasound/probe/us_settings.h"
#include "ultrasound/render/bmode_kernels.h"
#ifdef PCISIM_HAVE_CUDA
#include "ultrasound/render/cuda_bmode.h"
#endif

namespace pcisim::ultrasound {

// 8-bit grey, row-major, row 0 nearest the transducer, column 0 at the -lateral end
struct BModeImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;
};

// 8-bit grey PNG through png/; throws std::runtime_error naming the path
void write_png(const std::string& path, const BModeImage& image);

class BModeRenderer {
 public:
  // validates the settings (std::invalid_argument naming the field), the CT and the tissue map
  // (on the CT's grid, every tissue named in tissue_acoustics.h: the message names the one that
  // is not); keeps references to ct and the map, which must outlive the renderer. tissue ==
  // nullptr: the acoustic properties from the CT's HU. settings.renderer kCuda: std::runtime_error
  // when this build has no CUDA, no GPU is visible or there is no tissue map (the GPU samples
  // tissues, not HU)
  BModeRenderer(const anatomy::Volume& ct, const UsSettings& settings, const anatomy::TissueMap* tissue = nullptr);
  ~BModeRenderer();

  // the scanner's depth and overall gain from now on (the probe's knobs); throws
  // std::invalid_argument naming the field when out of range (us_settings.h), changing nothing
  void set_imaging(double depth_mm, double gain_db);

  // the deformed mesh's topology: builds the tet lookup grid (allocates)
  void set_mesh(const TetSnapshot& mesh);
  // one frame; deformed == nullptr: undeformed CT. A deformed snapshot must have the topology of
  // set_mesh() (set_mesh() is called on first use).
  const BModeImage& render(const ProbePose& pose, uint64_t seed, const TetSnapshot* deformed = nullptr);

  // the last frame's echo intensity per pixel, the envelope squared (row-major; relative to a
  // perfect plane reflector square to the beam at the face, after attenuation, transmission and
  // the point-spread function, before gain, TGC and compression)
  // (on the GPU it is copied back when first asked for after a frame, not with every frame)
  const std::vector<float>& echo_intensity() const;
  // the last frame in beam space (column = scanline, row = depth sample)
  const BModeImage& beam_image() const { return beam_; }
  const UsSettings& settings() const { return settings_; }
  // the GPU's passes in the last frame (ms, CUDA events; 0 on the CPU)
  float last_gpu_kernel_ms() const;
  // and each pass's (march, echo, axial PSF, lateral PSF, scan conversion; ms); nullptr on the CPU
  const float* last_gpu_pass_ms() const;
  // the pulse's length, max(2 wavelengths, CT voxel): the window over which a specular echo's
  // and the shadowing's impedance change is taken, and (a quarter of it, or half a CT voxel) the smoothing that
  // finds a boundary's middle
  double pulse_length_mm() const { return pulse_mm_; }

  // the largest half-width of a point-spread kernel, samples or scanlines: a PSF wider than a
  // third of it (21 samples sigma) is cut short of 3 sigma. The kernels repeat the image's edge
  // samples beyond it, so the outermost scanlines' and rows' speckle is a few dB brighter
  static constexpr int kMaxKernelHalf = kernels::kMaxKernelHalf;

 private:
  void build_geometry();
  void build_scan_conversion();
  Acoustics sample_hu(const double (&p_mm)[3]) const;
  // this renderer's arrays and settings as the kernels read them
  kernels::FrameView frame_view();

  const anatomy::Volume& ct_;
  // with a tissue map: its labels and each label's properties
  const anatomy::Volume* labels_ = nullptr;
  std::vector<Acoustics> label_acoustics_;
  kernels::LabelView label_view_;
  UsSettings settings_;
  Eigen::Matrix3d world_to_index_;
  double pulse_mm_ = 1.0, voxel_mm_ = 1.0;
  // per scanline, in the probe's frame (lateral, beam; mm): where it starts on the face, its direction
  std::vector<Eigen::Vector2d> line_start_, line_dir_;
  TetLocator locator_;
  bool have_mesh_ = false;
  // per sample, column-major (scanline by scanline): impedance, the path's step (mm of tissue per
  // screen sample, c / c0), the attenuation factor, the scatterers' amplitude sqrt(sigma), the
  // tissue's scatterer; the echo field before the PSF
  std::vector<float> z_, path_ratio_, attenuation_, scatter_amplitude_;
  std::vector<Cf> scatterer_, field_;
  // row-major: the field after the axial PSF; the intensity after both
  std::vector<Cf> axial_;
  std::vector<float> echo_;
  // the PSF: the axial kernel (peak 1); per row its lateral kernel (sum 1), the scanlines'
  // spacing there (mm) and the scatterers' scale (the diffuse intensity's mean is the tissue's
  // backscatter whatever the PSF's size)
  std::vector<float> axial_kernel_, lateral_kernel_, line_spacing_mm_, scatter_scale_;
  int axial_half_ = 0;
  // the smoothing of Z's change that finds a boundary's middle (a quarter pulse or half a voxel), and its result
  // per sample (column-major: scanlines are drawn on several threads)
  std::vector<float> steep_kernel_, steepness_;
  int steep_half_ = 0;
  std::vector<int> lateral_half_;
  BModeImage beam_, image_;
  // curvilinear display: per display pixel the beam-space cell (-1 outside the fan) and weights
  std::vector<int> convert_index_;
  std::vector<float> convert_fx_, convert_fy_;
  // settings_.threads threads (the caller one of them); started once
  realtime::RowPool pool_;
#ifdef PCISIM_HAVE_CUDA
  std::unique_ptr<cuda::BModeDevice> device_;  // the GPU's copy, with settings.renderer kCuda
  mutable bool echo_on_device_ = false;        // the last frame's echo_ not yet copied back
#endif
};

}  // namespace pcisim::ultrasound
