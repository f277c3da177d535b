#include "xray/fluoro/fluoroscopy.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "xray/overlay/tube_overlay.h"
#include "xray/overlay/wire_overlay.h"
#include "xray/fluoro/case_background.h"

namespace pcisim::xray {
namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

bool same_geometry(const DetectorGeometry& a, const DetectorGeometry& b) {
  return a.source_mm == b.source_mm && a.center_mm == b.center_mm && a.u == b.u && a.v == b.v &&
         a.pixel_mm == b.pixel_mm && a.width == b.width && a.height == b.height;
}

}  // namespace

struct FluoroscopyRenderer::Impl {
  anatomy::VesselTree tree;  // the bolus is rebuilt from it on restart()
  FluoroSpec spec;
  ContrastBolus bolus;
  DrrRenderer drr;
  DetectorChain chain;
  Image background, line, counts;
  Image compression, compression_tmp;  // per pose: the display's range-compression offset
  DetectorGeometry background_geometry;
  bool background_valid = false;
  int64_t background_renders = 0;
  uint64_t frames = 0;
  std::vector<float> window_scratch;
  std::unique_ptr<BeatingBackground> beat;
  std::vector<Eigen::Vector3d> wire_mm;
  WireSpec wire;
  FluoroFrameCost cost;
  // a move's quick projection and its refinement (set_move_preview)
  int preview_stride = 1, refine_rows = 64;
  int refine_next_row = -1;  // the next band's first row; -1: the background is whole
  Image preview, fine, band;

  // the range-compression offset of the background as it stands
  void compress_background(const DetectorGeometry& g) {
    const int radius_px = static_cast<int>(std::lround(spec.range_compression_mm / g.pixel_mm));
    range_compression_offset(background, radius_px, spec.range_compression, &compression_tmp, &compression);
    chain.set_offset(&compression);
  }
  // the display's window on the compressed background: set per pose from its first projection,
  // and once more when a quick one has been refined (never from contrast, so it never shifts
  // with an injection)
  void window_of_background(double* lo, double* hi) {
    for (size_t i = 0; i < compression_tmp.pixels.size(); ++i)
      compression_tmp.pixels[i] = background.pixels[i] - compression.pixels[i];
    display_window_for(compression_tmp, &window_scratch, lo, hi);
  }

  Impl(const anatomy::VesselTree& t, anatomy::Volume background, const FluoroSpec& s)
      : tree(t),
        spec(s),
        bolus(t, s.contrast),
        drr(std::move(background), s.projector),
        chain({.photons_per_pixel = s.photons_per_pixel, .blur_sigma_px = s.blur_sigma_px}),
        wire{.radius_mm = s.wire_radius_mm, .mu_per_mm = s.wire_mu_per_mm} {}
};

FluoroscopyRenderer::FluoroscopyRenderer(const anatomy::VesselTree& tree, const FluoroSpec& spec)
    : impl_(std::make_unique<Impl>(tree, thorax_background(tree, spec), spec)) {}

FluoroscopyRenderer::FluoroscopyRenderer(const anatomy::VesselTree& tree, anatomy::Volume background,
                                         const FluoroSpec& spec)
    : impl_(std::make_unique<Impl>(tree, std::move(background), spec)) {}

FluoroscopyRenderer::~FluoroscopyRenderer() = default;

void FluoroscopyRenderer::render(const FluoroInput& in, FluoroFrame& out) {
  Impl& m = *impl_;
  const bool pose_ok =
      std::isfinite(in.pose.primary_deg) && std::isfinite(in.pose.secondary_deg) && in.pose.isocenter_mm.allFinite();
  if (!pose_ok && !m.background_valid) {
    throw std::invalid_argument("FluoroscopyRenderer::render: non-finite C-arm pose and no earlier pose to keep");
  }
  // a non-finite pose keeps the last one (the x-ray thread must not stop on one bad sample)
  const DetectorGeometry g = pose_ok ? c_arm_geometry(m.spec.c_arm, in.pose) : m.background_geometry;
  auto t0 = std::chrono::steady_clock::now();
  m.cost = {};
  // 1. the static anatomy, re-projected only for a new geometry (or when invalidated)
  if (!m.background_valid || !same_geometry(g, m.background_geometry)) {
    if (m.preview_stride > 1) {
      // quick: every stride-th pixel, upsampled; refined by work_ahead()
      m.drr.render(coarse_detector(g, m.preview_stride), &m.preview);
      if (m.background.width != g.width || m.background.height != g.height) m.background.resize(g.width, g.height);
      upsample_bilinear(m.preview, m.preview_stride, &m.background);
      m.refine_next_row = 0;
    } else {
      m.drr.render(g, &m.background);
      m.refine_next_row = -1;
    }
    m.background_geometry = g;
    m.background_valid = true;
    ++m.background_renders;
    m.compress_background(g);
    double lo = 0, hi = 1;
    m.window_of_background(&lo, &hi);
    m.chain.set_window(lo, hi);  // from the background alone: contrast never shifts the brightness
    if (m.beat) m.beat->set_pose(g, m.background, m.refine_next_row >= 0 ? m.preview_stride : 0);
    m.cost.background_ms = ms_since(t0);
  }
  t0 = std::chrono::steady_clock::now();
  if (m.line.width != g.width || m.line.height != g.height) m.line.resize(g.width, g.height);
  if (m.beat && std::isfinite(in.heart_phase)) {
    m.beat->at_phase(in.heart_phase, &m.line);  // the heart where the physics left it
  } else {
    std::copy(m.background.pixels.begin(), m.background.pixels.end(), m.line.pixels.begin());
  }

  m.cost.beat_ms = ms_since(t0);
  t0 = std::chrono::steady_clock::now();
  // 2. iodine: mu x opacity x chord through each lumen segment holding contrast
  if (!in.vessel_points_m.empty()) m.bolus.move(in.vessel_points_m);
  m.bolus.update(in.time_s, in.injections);
  const auto& segs = m.bolus.segments();
  const auto& op = m.bolus.segment_opacity();
  for (size_t i = 0; i < segs.size(); ++i) {
    if (op[i] < kMinDrawnOpacity) continue;
    add_cone_segment(g, segs[i].a_mm, segs[i].b_mm, segs[i].ra_mm, segs[i].rb_mm, m.spec.iodine_mu_per_mm * op[i],
                     &m.line);
  }

  // 3. the wire: physics metres -> phantom millimetres (same LPS frame, same origin)
  m.wire_mm.resize(in.wire_m.size());
  for (size_t i = 0; i < in.wire_m.size(); ++i) m.wire_mm[i] = 1000.0 * in.wire_m[i];
  // the shaft, then the tip coil: segments within wire_tip_mm of the tip (the last node)
  double from_tip_mm = 0;
  for (size_t k = m.wire_mm.size(); k-- > 1;) {
    const Eigen::Vector3d& a = m.wire_mm[k - 1];
    const Eigen::Vector3d& b = m.wire_mm[k];
    const double mu = from_tip_mm < m.spec.wire_tip_mm ? m.spec.wire_tip_mu_per_mm : m.spec.wire_mu_per_mm;
    from_tip_mm += (b - a).norm();
    add_cone_segment(g, a, b, m.wire.radius_mm, m.wire.radius_mm, mu, &m.line);
  }
  project_polyline(g, m.wire_mm, &out.wire_px);

  m.cost.overlay_ms = ms_since(t0);
  t0 = std::chrono::steady_clock::now();
  // 4. quanta, noise, blur, log, window; the noise differs per frame, same for a seed
  const uint64_t key = (static_cast<uint64_t>(m.spec.seed) << 32) ^ m.frames++;
  m.chain.apply(m.line, key, &m.counts, &out.pixels);
  m.cost.detector_ms = ms_since(t0);

  out.width = g.width;
  out.height = g.height;
  out.geometry = g;
  if (pose_ok) out.pose = in.pose;
  out.time_s = in.time_s;
  // branch names: short strings (no heap), written into the slots already there
  const auto& bo = m.bolus.branch_opacity();
  const auto& names = m.bolus.branch_names();
  if (out.contrast_branches.capacity() < names.size()) out.contrast_branches.reserve(names.size());
  size_t k = 0;
  for (size_t b = 0; b < bo.size(); ++b) {
    if (bo[b] <= m.spec.contrast.visible_opacity) continue;
    if (k < out.contrast_branches.size()) {
      out.contrast_branches[k] = names[b];
    } else {
      out.contrast_branches.push_back(names[b]);
    }
    ++k;
  }
  out.contrast_branches.resize(k);
}

int64_t FluoroscopyRenderer::background_renders() const {
  return impl_->background_renders;
}
void FluoroscopyRenderer::invalidate_background() {
  impl_->background_valid = false;
  impl_->refine_next_row = -1;  // the next frame projects again
}
void FluoroscopyRenderer::set_beat(const BeatSamples& samples, const BeatingBackgroundOptions& options,
                                   std::shared_ptr<const BeatChanges> changes) {
  impl_->beat = std::make_unique<BeatingBackground>(impl_->drr.attenuation(), samples, options, std::move(changes));
  impl_->background_valid = false;
  impl_->refine_next_row = -1;
}
const BeatingBackground* FluoroscopyRenderer::beat() const {
  return impl_->beat.get();
}
int FluoroscopyRenderer::work_ahead() {
  Impl& m = *impl_;
  if (!m.background_valid) return 0;
  if (m.refine_next_row >= 0) {
    // one band of the whole projection; the last one swaps it in
    const DetectorGeometry& g = m.background_geometry;
    if (m.fine.width != g.width || m.fine.height != g.height) m.fine.resize(g.width, g.height);
    const int rows = std::min(m.refine_rows, g.height - m.refine_next_row);
    m.drr.render(detector_rows(g, m.refine_next_row, rows), &m.band);
    std::copy(m.band.pixels.begin(), m.band.pixels.end(),
              m.fine.pixels.begin() + static_cast<std::ptrdiff_t>(m.refine_next_row) * g.width);
    m.refine_next_row += rows;
    if (m.refine_next_row >= g.height) {
      if (m.beat) m.beat->replace_static(m.background, m.fine);
      std::swap(m.background, m.fine);
      m.compress_background(g);
      m.refine_next_row = -1;
      // the window found again on the whole projection: the settled frame is the one a whole
      // projection would show (one step in brightness, with the sharpening; contrast plays no part)
      double lo = 0, hi = 1;
      m.window_of_background(&lo, &hi);
      m.chain.set_window(lo, hi);
    }
    return 1;
  }
  return m.beat ? m.beat->fill_ahead() : 0;
}
void FluoroscopyRenderer::set_move_preview(const MovePreview& preview) {
  if (preview.stride < 1 || preview.stride > 8)
    throw std::invalid_argument("move preview: stride must be 1-8, not " + std::to_string(preview.stride));
  if (preview.rows_per_step < 1)
    throw std::invalid_argument("move preview: rows_per_step must be >= 1, not " +
                                std::to_string(preview.rows_per_step));
  impl_->preview_stride = preview.stride;
  impl_->refine_rows = preview.rows_per_step;
}
bool FluoroscopyRenderer::background_refined() const {
  return impl_->refine_next_row < 0;
}
void FluoroscopyRenderer::set_c_arm(const CArmSpec& c_arm) {
  impl_->spec.c_arm = c_arm;
}
void FluoroscopyRenderer::restart(const FluoroSpec& spec, bool keep_beat) {
  Impl& m = *impl_;
  const FluoroSpec& old = m.spec;
  if (spec.volume_dims != old.volume_dims || spec.volume_spacing_mm != old.volume_spacing_mm ||
      spec.projector.projector != old.projector.projector ||
      spec.projector.trilinear.step_voxels != old.projector.trilinear.step_voxels ||
      spec.projector.trilinear.slices != old.projector.trilinear.slices)
    throw std::invalid_argument(
        "FluoroscopyRenderer::restart: another background volume or projector needs a new renderer");
  // the pose's projection, its range compression and window stay valid when none of their inputs moved
  const bool keep =
      old.c_arm.width == spec.c_arm.width && old.c_arm.height == spec.c_arm.height &&
      old.c_arm.pixel_mm == spec.c_arm.pixel_mm && old.c_arm.source_to_image_mm == spec.c_arm.source_to_image_mm &&
      old.c_arm.source_to_axis_mm == spec.c_arm.source_to_axis_mm && old.range_compression == spec.range_compression &&
      old.range_compression_mm == spec.range_compression_mm;
  const double lo = m.chain.window_lo(), hi = m.chain.window_hi();
  m.spec = spec;
  m.bolus = ContrastBolus(m.tree, spec.contrast);
  m.chain = DetectorChain({.photons_per_pixel = spec.photons_per_pixel, .blur_sigma_px = spec.blur_sigma_px});
  m.chain.set_window(lo, hi);
  if (m.background_valid) m.chain.set_offset(&m.compression);
  m.wire = {.radius_mm = spec.wire_radius_mm, .mu_per_mm = spec.wire_mu_per_mm};
  m.frames = 0;
  if (!keep_beat) m.beat.reset();
  if (!keep) {
    m.background_valid = false;
    m.refine_next_row = -1;
  }
}
const FluoroFrameCost& FluoroscopyRenderer::last_frame_cost() const {
  return impl_->cost;
}
const Image& FluoroscopyRenderer::line_integrals() const {
  return impl_->line;
}
const Image& FluoroscopyRenderer::detector_counts() const {
  return impl_->counts;
}
const ContrastBolus& FluoroscopyRenderer::contrast() const {
  return impl_->bolus;
}
double FluoroscopyRenderer::window_lo() const {
  return impl_->chain.window_lo();
}
double FluoroscopyRenderer::window_hi() const {
  return impl_->chain.window_hi();
}

}  // namespace pcisim::xray
