#pragma once
// Fluoroscopy frames as a cath-lab monitor shows them: the static anatomy projected once per
// C-arm pose (blood-filled lumens), then per frame the iodine in the coronary tree (where the
// bolus has reached) and the wire added analytically as chord length x mu through thin tubes,
// Beer-Lambert with a photon count per pixel, Poisson quantum noise, detector blur, log and a
// display window so radiopaque structures are dark. The x-ray thread owns one renderer.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "anatomy/vessel/vessel_tree.h"
#include "xray/fluoro/beating_background.h"
#include "xray/fluoro/contrast_bolus.h"
#include "xray/fluoro/detector_chain.h"
#include "xray/geometry/c_arm.h"
#include "xray/geometry/detector_geometry.h"
#include "xray/render/drr_renderer.h"

namespace pcisim::xray {

// the background projector's default below: one sample per voxel plane (Joseph's method,
// TrilinearOptions::slices); step_voxels 1 where a scene asks for steps instead
inline DrrRendererOptions voxel_plane_samples() {
  DrrRendererOptions o;
  o.trilinear.step_voxels = 1.0;
  o.trilinear.slices = true;
  return o;
}

struct FluoroSpec {
  CArmSpec c_arm;  // detector size, pitch, SID, SAD
  // background projector; one sample per voxel plane: closer to the exact projection than
  // trilinear 1-voxel steps on the phantom (0.065 vs 0.080 % RMSE) in a third of the time on 2
  // cores (docs/benchmarks/xray.md; trilinear at 0.5 voxel: 0.079 %, 1.5 x the 1-voxel time)
  DrrRendererOptions projector = voxel_plane_samples();
  std::array<int64_t, 3> volume_dims{256, 256, 128};  // phantom resolution for the background
  double volume_spacing_mm = 1.4;
  double photons_per_pixel = 2000;  // incident quanta per pixel at the detector (0: no noise)
  double blur_sigma_px = 0.7;       // detector blur
  // display dynamic range compression: this fraction of the background's low-pass (over
  // range_compression_mm on the detector) is taken out of the log image; 0: a plain log window
  double range_compression = 0.6;
  double range_compression_mm = 15;
  // undiluted contrast (~350 mg iodine/ml) near 60 keV: mu/rho of iodine ~7.6 cm^2/g (NIST XCOM,
  // Hubbell & Seltzer) x 0.35 g/ml ~ 0.27 /mm; a hand injection outruns coronary flow, so the
  // lumen holds nearly undiluted contrast (the bolus model scales this by its opacity)
  double iodine_mu_per_mm = 0.25;
  double wire_radius_mm = 0.1778;  // 0.014"
  double wire_mu_per_mm = 0.95;    // stainless steel near 60 keV
  // the radiopaque tip: a platinum-tungsten coil over the distal ~30 mm. Platinum near 60 keV:
  // mu/rho ~3.4 cm^2/g (NIST XCOM) x 21.4 g/cm^3 ~ 7 /mm solid; a wound coil fills ~half its
  // cross-section. 0 mm: no tip coil
  double wire_tip_mm = 30;
  double wire_tip_mu_per_mm = 3.5;
  uint32_t seed = 1;           // phantom and noise
  ContrastBolusSpec contrast;  // bolus velocity, washout, taper, flows
};

struct FluoroInput {
  double time_s = 0;  // simulation time of the frame
  CArmPose pose;
  std::span<const Eigen::Vector3d> wire_m = {};        // wire nodes, physics frame (metres, LPS); may be empty
  std::span<const ContrastInjection> injections = {};  // every injection so far (the renderer fades old ones)
  // the coronary centerline points where the beating heart has carried them (metres, tree order,
  // as physics' VesselSkin gives them); empty: the tree at rest
  std::span<const Eigen::Vector3d> vessel_points_m = {};
  // the cardiac phase [0, 1) the physics step left (snapshot heart_phase); the beating
  // background (set_beat) draws the heart there. NaN: the background at rest
  double heart_phase = std::numeric_limits<double>::quiet_NaN();
};

struct FluoroFrame {
  int width = 0, height = 0;
  std::vector<uint16_t> pixels;  // row-major, row 0 first; dark = radiopaque
  DetectorGeometry geometry;     // the projection the frame used
  CArmPose pose;
  double time_s = 0;
  std::vector<Eigen::Vector2d> wire_px;        // the wire's projected polyline (column, row); tip last
  std::vector<std::string> contrast_branches;  // branches holding visible contrast
};

// what the last render() spent, ms of wall time (the dataset benchmark's stages)
struct FluoroFrameCost {
  double background_ms = 0;  // the static projection (0 when the pose's was reused)
  double beat_ms = 0;        // the beating background at the frame's phase (its bins projected if missing)
  double overlay_ms = 0;     // iodine and wire, analytic
  double detector_ms = 0;    // quanta, noise, blur, log, window
};

// a C-arm move's quick first frame (FluoroscopyRenderer::set_move_preview): the interactive
// loops' setting. Stride 8 projects 1/64 of the rays: in a running session on 2 cores stride 4's
// first frame reached 101 ms p99 against issue #36's 100 ms (docs/benchmarks/stalls.md; the
// renderer alone and what the coarser frame costs in pixels: docs/benchmarks/xray-beating.md);
// 64 rows of 512 are an eighth of the whole projection per frame
struct MovePreview {
  int stride = 8;          // 1-8; 1: no quick projection
  int rows_per_step = 64;  // >= 1
};

class FluoroscopyRenderer {
 public:
  // builds the thorax phantom around `tree` and prepares the projector (seconds at most)
  FluoroscopyRenderer(const anatomy::VesselTree& tree, const FluoroSpec& spec);
  // the same over a given background CT (a case's: xray/fluoro/case_background.h)
  FluoroscopyRenderer(const anatomy::VesselTree& tree, anatomy::Volume background, const FluoroSpec& spec);
  ~FluoroscopyRenderer();

  // renders one frame into out; after the first frame of a given size nothing is allocated
  void render(const FluoroInput& in, FluoroFrame& out);

  // how many background projections were made (a pose change makes one; a frame with the same
  // pose reuses it)
  int64_t background_renders() const;
  // the next frame re-projects the background (heart motion, a changed volume)
  void invalidate_background();
  // from now on the background beats: the CT warped by one cycle of the heart's motion (samples
  // in the CT's frame, mm), projected per phase bin for each pose and blended per frame at the
  // input's heart_phase; the next frame re-projects. Throws std::invalid_argument when the
  // samples or options are bad (naming the field)
  // `changes`: the bins' changes another renderer's background made over the same CT, samples and
  // options (beat()->changes()), shared instead of written again
  void set_beat(const BeatSamples& samples, const BeatingBackgroundOptions& options = {},
                std::shared_ptr<const BeatChanges> changes = nullptr);
  const BeatingBackground* beat() const;  // null while the background stands still
  // a C-arm move's first frame from a quick projection (issue #36: the whole one held the picture
  // for ~390 ms on 2 cores): the static background projected on the detector of every stride-th
  // pixel (coarse_detector) and upsampled, then projected whole in bands of rows_per_step rows,
  // one band per work_ahead(), swapped in once complete. Every frame is the true projection of
  // its pose, at the resolution reached. Until this is called, stride 1: the whole projection at once, as
  // datasets want. Throws std::invalid_argument naming the field out of its range
  void set_move_preview(const MovePreview& preview);
  bool background_refined() const;  // false while a move's quick projection is shown
  // the work a frame leaves for after it is out: one band of a move's projection while one is
  // pending, else up to the beat's fill_per_frame phase bins the current pose still lacks (render()
  // projects only the bins its own frame needs, so a frame after a C-arm move is not held up by
  // bins it does not show). How many pieces it did, 0 when nothing is left
  int work_ahead();
  // a new detector or SID/SAD; the next frame re-projects the background if the geometry changed
  void set_c_arm(const CArmSpec& c_arm);
  // a fresh run over the same background volume and projector (a dataset's next sample): every
  // other field of `spec` takes effect, the noise starts again at frame 0 of spec.seed, the beat
  // is dropped unless `keep_beat` (the same heart: its phase bins stay cached per pose), and the
  // pose's background is kept only when nothing it depends on changed. Throws
  // std::invalid_argument when spec asks for another volume or projector (build a new renderer)
  void restart(const FluoroSpec& spec, bool keep_beat = false);
  const FluoroFrameCost& last_frame_cost() const;

  // the last frame's pieces, for tests and ground truth: noiseless line integrals (background +
  // contrast + wire), detector counts after noise and blur, and the contrast model's state
  const Image& line_integrals() const;
  const Image& detector_counts() const;
  const ContrastBolus& contrast() const;
  double window_lo() const;  // display window (line-integral units): lo white, hi black
  double window_hi() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pcisim::xray
