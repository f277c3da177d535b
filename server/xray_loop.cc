#include "server/xray_loop.h"

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "anatomy/case/heart_center.h"
#include "server/beat_samples.h"
#include "xray/fluoro/case_background.h"
#include "protocol/channels.h"
#include "realtime/clock.h"
#include "realtime/deadline_schedule.h"

namespace pcisim::server {
namespace {
// how often the loop looks for a C-arm move between pulses while the beam is on
constexpr int64_t kMoveWatchNs = 5'000'000;
}  // namespace

XrayLoop::XrayLoop(const Scene& scene, const anatomy::Case& anatomy, SharedState& state, lcm::LCM* images,
                   const xray::BeatSamples* beat)
    : spec_(*scene.xray), state_(state), images_(images) {
  // the table brings the case's heart to the isocentre (a patient's CT is in scanner coordinates)
  spec_.initial_pose.isocenter_mm = anatomy::heart_center_mm(anatomy);
  // the case physics runs on: its vessels for the contrast, its CT (or the thorax) behind them
  renderer_ = std::make_unique<xray::FluoroscopyRenderer>(anatomy.vessels,
                                                          xray::background_volume(anatomy, spec_.fluoro), spec_.fluoro);
  if (beat) {
    try {
      renderer_->set_beat(*beat, beat_options(spec_));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("xray.heart_phase_bins: the beating background cannot be built (") +
                                  e.what() + "); 0 keeps the background still");
    }
  }
  injections_.reserve(SharedState::kMaxInjections);
  state_.carm_primary_deg = state_.carm_target_primary_deg = spec_.initial_pose.primary_deg;
  state_.carm_secondary_deg = state_.carm_target_secondary_deg = spec_.initial_pose.secondary_deg;
  min_move_interval_ns_ = static_cast<int64_t>(scene.session.min_carm_move_interval_s * 1e9);
  state_.xray_enabled = true;
  // one frame now: projects the background for the initial pose and sizes every buffer, so the
  // first press of the pedal gets frames at once
  xray::FluoroInput warm_up;
  warm_up.pose = spec_.initial_pose;
  warm_up.heart_phase = beat ? 0.0 : NAN;
  renderer_->render(warm_up, frame_);
  while (renderer_->work_ahead() > 0) {}
  // from here on a C-arm move shows a quick projection first (the pose above is whole)
  renderer_->set_move_preview(xray::MovePreview{});
}

// a move re-projects the background (quick, then whole over the next frames): a flood of targets
// moves the C-arm at most once per interval, to the newest target; the rest are coalesced
bool XrayLoop::move_due(int64_t now_ns) const {
  const int64_t seq = state_.carm_target_seq.load(std::memory_order_acquire);
  return (seq & 1) == 0 && seq != applied_target_seq_ && now_ns - last_move_ns_ >= min_move_interval_ns_;
}

void XrayLoop::apply_carm_target() {
  const int64_t seq = state_.carm_target_seq.load(std::memory_order_acquire);
  const int64_t now_ns = realtime::monotonic_ns();
  if (!move_due(now_ns)) return;
  const double primary = state_.carm_target_primary_deg.load(), secondary = state_.carm_target_secondary_deg.load();
  if (state_.carm_target_seq.load(std::memory_order_acquire) != seq) return;  // torn: the next frame retries
  applied_target_seq_ = seq;
  last_move_ns_ = now_ns;
  state_.carm_primary_deg = primary;
  state_.carm_secondary_deg = secondary;
  state_.carm_moves.fetch_add(1, std::memory_order_relaxed);
  if (metrics_) metrics_->record_carm(primary, secondary, now_ns);
}

void XrayLoop::render_and_publish(bool cine) {
  // newest snapshot, current C-arm, every injection so far
  state_.snapshot_for_xray.refresh();
  const physics::WorldSnapshot& snap = state_.snapshot_for_xray.read_slot();
  const int n = state_.injections.load(std::memory_order_acquire);
  while (static_cast<int>(injections_.size()) < n) {
    xray::ContrastInjection inj;
    inj.start_s = state_.injection_start_s[injections_.size()];
    const size_t k = injections_.size();
    inj.duration_s = state_.injection_duration_s[k] > 0 ? state_.injection_duration_s[k] : spec_.injection_duration_s;
    inj.volume_ml = state_.injection_volume_ml[k] > 0 ? state_.injection_volume_ml[k] : spec_.injection_volume_ml;
    injections_.push_back(inj);
  }
  apply_carm_target();
  xray::FluoroInput in;
  in.time_s = snap.time_s;
  in.pose = spec_.initial_pose;
  in.pose.primary_deg = state_.carm_primary_deg.load();
  in.pose.secondary_deg = state_.carm_secondary_deg.load();
  in.wire_m = snap.wire_nodes_m;
  in.vessel_points_m = snap.vessel_points_m;
  if (renderer_->beat()) in.heart_phase = snap.heart_phase;
  if (spec_.contrast) in.injections = injections_;
  const int64_t t0 = realtime::monotonic_ns();
  renderer_->render(in, frame_);
  state_.xray_render_ns.record(realtime::monotonic_ns() - t0);
  // the debrief keeps the frame that showed the vessels best, to draw the tip's path on
  if (metrics_ && !frame_.contrast_branches.empty())
    metrics_->record_frame(frame_.pixels.data(), frame_.width, frame_.height, frame_.geometry,
                           // the heart's phase the vessels in the frame are at (the background may stand still)
                           snap.vessel_points_m.empty() ? std::nan("") : snap.heart_phase,
                           static_cast<int>(frame_.contrast_branches.size()), realtime::monotonic_ns());
  state_.xray_frames.fetch_add(1, std::memory_order_relaxed);
  if (!images_) {
    renderer_->work_ahead();
    return;
  }

  // the frame with its geometry and ground truth
  auto& m = msg_;
  const auto& g = frame_.geometry;
  m.utime = realtime::monotonic_us();
  m.seq = seq_++;
  m.width = frame_.width;
  m.height = frame_.height;
  m.pixel_format = pcisim_lcm::xray_frame_t::FORMAT_GRAY16;
  m.primary_angle_deg = frame_.pose.primary_deg;
  m.secondary_angle_deg = frame_.pose.secondary_deg;
  m.source_to_image_mm = spec_.fluoro.c_arm.source_to_image_mm;
  m.source_to_axis_mm = spec_.fluoro.c_arm.source_to_axis_mm;
  m.pixel_mm = g.pixel_mm;
  for (int k = 0; k < 3; ++k) {
    m.source_mm[k] = g.source_mm[k];
    m.detector_center_mm[k] = g.center_mm[k];
    m.detector_u[k] = g.u[k];
    m.detector_v[k] = g.v[k];
  }
  m.sim_time_s = frame_.time_s;
  m.cine = cine ? 1 : 0;
  m.cine_run = cine ? cine_run_ : -1;
  const size_t nodes = snap.wire_nodes_m.size();
  m.num_wire_points = static_cast<int32_t>(nodes);
  // the message's nested vectors keep their size from frame to frame: only a change of the
  // wire's node count builds new rows
  if (m.wire_mm.size() != nodes) m.wire_mm.assign(nodes, std::vector<float>(3));
  if (m.wire_px.size() != nodes) m.wire_px.assign(nodes, std::vector<float>(2));
  for (size_t i = 0; i < nodes; ++i) {
    for (int k = 0; k < 3; ++k) m.wire_mm[i][k] = static_cast<float>(snap.wire_nodes_m[i][k] * 1e3);
    const bool has_px = i < frame_.wire_px.size();
    m.wire_px[i][0] = has_px ? static_cast<float>(frame_.wire_px[i][0]) : NAN;
    m.wire_px[i][1] = has_px ? static_cast<float>(frame_.wire_px[i][1]) : NAN;
  }
  m.num_contrast_branches = static_cast<int32_t>(frame_.contrast_branches.size());
  m.contrast_branches = frame_.contrast_branches;
  m.num_bytes = static_cast<int32_t>(frame_.pixels.size() * 2);
  m.data.resize(static_cast<size_t>(m.num_bytes));
  std::memcpy(m.data.data(), frame_.pixels.data(), m.data.size());  // little-endian uint16
  publisher_.publish(*images_, channel_, m);
  // after the frame is out: one more of the pose's phase bins, until it has them all
  renderer_->work_ahead();
}

void XrayLoop::run() {
  // the schedule runs at the fastest rate asked for; slower pulse rates skip ticks
  const double tick_hz = std::max(spec_.pulse_rate_fps, spec_.cine_rate_fps);
  realtime::DeadlineSchedule schedule(realtime::monotonic_ns(), static_cast<int64_t>(std::llround(1e9 / tick_hz)));
  int64_t tick = 0, last_on_ns = 0;
  bool on = false, first_pulse_counted = false;
  while (!state_.stop.load(std::memory_order_relaxed)) {
    // while the beam is on, a C-arm move is shown at once rather than at the next pulse (up to a
    // pulse period later, 67 ms at 15/s; issue #36): the wait is cut into naps that look for one
    bool moved = false;
    for (int64_t now_ns = realtime::monotonic_ns(); now_ns < schedule.deadline_ns() && !moved;
         now_ns = realtime::monotonic_ns()) {
      moved = on && move_due(now_ns);
      if (!moved) realtime::sleep_until_ns(std::min(schedule.deadline_ns(), now_ns + kMoveWatchNs));
    }
    const int64_t wake_ns = realtime::monotonic_ns();
    const bool cine = state_.instrument_pedal_down(state_.cine_instrument, wake_ns) || state_.cine_console;
    on = cine || state_.instrument_pedal_down(state_.fluoro_pedal_instrument, wake_ns) || state_.fluoro_pedal_console;
    if (cine && !was_cine_) ++cine_run_;
    was_cine_ = cine;
    if (metrics_)
      metrics_->record_pedals(
          state_.instrument_pedal_down(state_.fluoro_pedal_instrument, wake_ns) || state_.fluoro_pedal_console, cine,
          wake_ns);
    const double rate = cine ? spec_.cine_rate_fps : spec_.pulse_rate_fps;
    const auto every = std::max<int64_t>(1, std::llround(tick_hz / rate));
    const bool pulse = tick % every == 0;
    if (on) {
      // beam time: wall time with the pedal down, wake to wake (ticks a busy machine skipped still
      // count), and the first pulse of each press its period, so that n pulses stand for n periods
      int64_t beam_ns = last_on_ns ? wake_ns - last_on_ns : 0;
      last_on_ns = wake_ns;
      if (pulse && !first_pulse_counted) {
        beam_ns += every * schedule.period_ns();
        first_pulse_counted = true;
      }
      state_.xray_on_ns.fetch_add(beam_ns, std::memory_order_relaxed);
      if (metrics_)
        metrics_->record_beam_time(beam_ns * 1e-9, cine, state_.carm_primary_deg.load(),
                                   state_.carm_secondary_deg.load());
      if (moved || pulse) render_and_publish(cine);
    } else {
      last_on_ns = 0;
      first_pulse_counted = false;
    }
    // an extra frame: the pulse it came before still comes on time, unless the move's frame ran
    // past it (then that pulse's frame is the move's)
    const bool extra = moved && realtime::monotonic_ns() < schedule.deadline_ns();
    if (on && pulse && !extra) {
      state_.xray_pulses.fetch_add(1, std::memory_order_relaxed);
      if (metrics_) metrics_->record_pulse(cine);
    }
    if (extra) continue;
    ++tick;
    schedule.complete(realtime::monotonic_ns());
  }
}

}  // namespace pcisim::server
