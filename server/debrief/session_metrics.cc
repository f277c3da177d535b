#include "server/debrief/session_metrics.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <fmt/format.h>

#include "anatomy/vessel/vessel_tree.h"
#include "xray/geometry/c_arm.h"

namespace pcisim::server {

namespace {
// the IRP lies this far from the isocentre toward the focal spot (IEC 60601-2-43)
constexpr double kIrpBeforeIsocentreMm = 150.0;
// two poses closer than this in both angles are one pose
constexpr double kSamePoseDeg = 0.5;
}  // namespace

BeamGeometry beam_geometry(double source_to_axis_mm, double source_to_image_mm, double detector_width_mm,
                           double detector_height_mm) {
  BeamGeometry g;
  g.source_to_irp_mm = source_to_axis_mm - kIrpBeforeIsocentreMm;
  // the field's area scales with the square of the distance from the focal spot
  const double scale = g.source_to_irp_mm / source_to_image_mm;
  g.field_area_at_irp_cm2 = detector_width_mm * detector_height_mm * scale * scale * 1e-2;
  return g;
}

const char* timeline_kind_name(TimelineKind k) {
  switch (k) {
    case TimelineKind::kFluoroOn:
      return "fluoro_on";
    case TimelineKind::kFluoroOff:
      return "fluoro_off";
    case TimelineKind::kCineOn:
      return "cine_on";
    case TimelineKind::kCineOff:
      return "cine_off";
    case TimelineKind::kCArm:
      return "carm";
    case TimelineKind::kContrast:
      return "contrast";
    case TimelineKind::kForceEvent:
      return "force_event";
    case TimelineKind::kReset:
      return "wire_restart";
    case TimelineKind::kProlapse:
      return "prolapse";
    case TimelineKind::kBuckling:
      return "buckling";
  }
  return "?";
}

SessionMetrics::SessionMetrics() : timeline_(kMaxTimeline), track_(kMaxTrack) {}

double SessionMetrics::session_s(int64_t now_ns) const {
  return start_ns_ != 0 ? static_cast<double>(now_ns - start_ns_) * 1e-9 : 0.0;
}

void SessionMetrics::add_event(TimelineKind kind, double a, double b, int64_t now_ns) {
  if (timeline_count_ >= kMaxTimeline) {
    ++f_.timeline_dropped;
    return;
  }
  timeline_[timeline_count_++] = {session_s(now_ns), kind, a, b};
}

void SessionMetrics::begin_pipeline(const DebriefParams& params, const anatomy::VesselTree& tree, bool tip_forces_known,
                                    const BeamGeometry& beam, int64_t now_ns, int detector_width, int detector_height) {
  std::lock_guard lock(mutex_);
  if (start_ns_ == 0) {
    start_ns_ = now_ns;
  } else {
    ++pipeline_;
  }
  // the frame store sized for this scene's detector (nothing is allocated when a frame comes)
  const size_t pixels = static_cast<size_t>(std::max(detector_width, 0)) * std::max(detector_height, 0);
  if (angiogram_.pixels.capacity() < pixels) angiogram_.pixels.reserve(pixels);
  if (incoming_.capacity() < pixels) incoming_.reserve(pixels);
  params_ = params;
  beam_ = beam;
  forces_known_ = tip_forces_known;
  f_.tip_forces_known = f_.tip_forces_known || tip_forces_known;
  f_.target_branch = params.target_branch;
  // the route: the target and every branch it leaves from, up to the root
  on_route_.assign(tree.branches.size(), 0);
  target_ = params.target_branch.empty() ? -1 : tree.find(params.target_branch);
  for (int b = target_, guard = 0; b >= 0 && b < static_cast<int>(tree.branches.size()) && guard < 10000; ++guard) {
    on_route_[b] = 1;
    b = tree.branches[b].parent;
  }
  f_.has_target = f_.has_target || target_ >= 0;
  // the wire of the new pipeline starts afresh
  end_episodes();
  if (have_last_) {
    ++f_.resets;
    add_event(TimelineKind::kReset, 0, 0, now_ns);
  }
  have_last_ = false;
}

void SessionMetrics::record_beam_time(double seconds, bool cine, double primary_deg, double secondary_deg) {
  if (!(seconds > 0.0) || !std::isfinite(seconds)) return;
  std::lock_guard lock(mutex_);
  f_.fluoro_time_s += seconds;
  if (cine) f_.cine_time_s += seconds;
  for (int i = 0; i < pose_count_; ++i) {
    CArmUse& p = poses_[i];
    if (std::abs(p.primary_deg - primary_deg) < kSamePoseDeg &&
        std::abs(p.secondary_deg - secondary_deg) < kSamePoseDeg) {
      p.beam_s += seconds;
      return;
    }
  }
  if (pose_count_ < kMaxPoses) poses_[pose_count_++] = {primary_deg, secondary_deg, seconds};
}

// air kerma at the IRP a pulse: K = Y(1 m) (mA s) (1 m / d_IRP)^2 (the inverse-square law from
// the tube's output at 1 m; docs/debrief.md), and the dose-area product K A_IRP
void SessionMetrics::record_pulse(bool cine) {
  std::lock_guard lock(mutex_);
  (cine ? f_.cine_frames : f_.fluoro_pulses) += 1;
  const double mas = cine ? params_.cine_mas_per_frame : params_.fluoro_mas_per_pulse;
  const double d_m = beam_.source_to_irp_mm * 1e-3;
  const double kerma_ugy = params_.tube_output_ugy_per_mas_at_1m * mas / (d_m * d_m);
  f_.air_kerma_mgy += kerma_ugy * 1e-3;
  f_.dap_gycm2 += kerma_ugy * 1e-6 * beam_.field_area_at_irp_cm2;
}

void SessionMetrics::record_pedals(bool fluoro, bool cine, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  if (fluoro != fluoro_on_) add_event(fluoro ? TimelineKind::kFluoroOn : TimelineKind::kFluoroOff, 0, 0, now_ns);
  if (cine != cine_on_) {
    add_event(cine ? TimelineKind::kCineOn : TimelineKind::kCineOff, 0, 0, now_ns);
    if (cine) ++f_.cine_runs;
  }
  fluoro_on_ = fluoro;
  cine_on_ = cine;
}

void SessionMetrics::record_carm(double primary_deg, double secondary_deg, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  add_event(TimelineKind::kCArm, primary_deg, secondary_deg, now_ns);
}

// (the x-ray thread alone calls this: incoming_ is its own; the copy is made outside the lock, so
// the send thread never waits behind half a megabyte)
void SessionMetrics::record_frame(const uint16_t* pixels, int width, int height, const xray::DetectorGeometry& geometry,
                                  double heart_phase, int contrast_branches, int64_t now_ns) {
  const size_t n = static_cast<size_t>(std::max(width, 0)) * std::max(height, 0);
  if (n == 0 || contrast_branches <= 0) return;
  {
    std::lock_guard lock(mutex_);
    if (n > angiogram_.pixels.capacity() || n > incoming_.capacity()) return;  // (nothing allocated here)
    // the frame with the most contrast (a later one as good replaces it): where the vessels show;
    // a new scene's first one replaces the last scene's
    const bool newer_scene = angiogram_.time_s >= 0.0 && angiogram_.pipeline != pipeline_;
    if (!newer_scene && contrast_branches < angiogram_.contrast_branches) return;
  }
  incoming_.assign(pixels, pixels + n);
  std::lock_guard lock(mutex_);
  angiogram_.pixels.swap(incoming_);
  angiogram_.width = width;
  angiogram_.height = height;
  angiogram_.geometry = geometry;
  angiogram_.heart_phase = heart_phase;
  angiogram_.time_s = session_s(now_ns);
  angiogram_.contrast_branches = contrast_branches;
  angiogram_.pipeline = pipeline_;
}

void SessionMetrics::record_injection(double volume_ml, int64_t now_ns) {
  std::lock_guard lock(mutex_);
  ++f_.contrast_injections;
  f_.contrast_ml += volume_ml;
  add_event(TimelineKind::kContrast, volume_ml, 0, now_ns);
}

void SessionMetrics::update_episode(Episode& e, bool on, double value, double sim_time_s, int64_t now_ns) {
  if (on) {
    if (!e.on) {
      e.on = true;
      e.start_s = session_s(now_ns);
      e.sim_start_s = sim_time_s;
      e.peak = value;
    }
    e.peak = std::max(e.peak, value);
  } else if (e.on) {
    end_episode(e, sim_time_s);  // it ends at this state
  }
}

void SessionMetrics::end_episode(Episode& e, double sim_end_s) {
  ++e.count;
  // (listed at its start, when it ends: the timeline is sorted by time when it is read)
  if (timeline_count_ < kMaxTimeline) {
    timeline_[timeline_count_++] = {e.start_s, e.kind, e.peak, sim_end_s - e.sim_start_s};
  } else {
    ++f_.timeline_dropped;
  }
  e.on = false;
}

// the wire starts over (a reset, a new scene): what was going on ends with its last state
void SessionMetrics::end_episodes() {
  for (Episode* e : {&force_, &fold_, &feed_})
    if (e->on) end_episode(*e, last_time_s_);
  feed_count_ = 0;
}

namespace {

// the point `back_m` along the wire behind its tip (nodes proximal to distal); false when the wire
// is shorter
bool point_behind_tip(const std::vector<Eigen::Vector3d>& nodes, double back_m, Eigen::Vector3d* p) {
  double walked = 0.0;
  for (size_t i = nodes.size() - 1; i > 0; --i) {
    const double l = (nodes[i] - nodes[i - 1]).norm();
    if (walked + l >= back_m && l > 0.0) {
      *p = nodes[i] + (back_m - walked) / l * (nodes[i - 1] - nodes[i]);
      return true;
    }
    walked += l;
  }
  return false;
}

// the angle (deg) between the wire's last 5 mm and its direction 10-30 mm behind the tip: near 0
// along a vessel, 180 where the tip has turned back along the wire; 0 for a wire shorter than that
double fold_angle_deg(const std::vector<Eigen::Vector3d>& nodes) {
  Eigen::Vector3d p5, p10, p30;
  if (nodes.size() < 2 || !point_behind_tip(nodes, 5e-3, &p5) || !point_behind_tip(nodes, 10e-3, &p10) ||
      !point_behind_tip(nodes, 30e-3, &p30))
    return 0.0;
  const Eigen::Vector3d tip = nodes.back() - p5, body = p10 - p30;
  const double n = tip.norm() * body.norm();
  if (!(n > 0.0)) return 0.0;
  return std::acos(std::clamp(tip.dot(body) / n, -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

}  // namespace

// each interval between two wire states is booked with the earlier state's branch and force
// (the state holds until the next one); a state whose step does not follow the last one's (a
// reset, a new scene) starts the path afresh
void SessionMetrics::record_wire(const physics::WorldSnapshot& s, double primary_deg, double secondary_deg,
                                 int64_t now_ns) {
  std::lock_guard lock(mutex_);
  ++f_.wire_states;
  if (s.wire_nodes_m.empty() || !s.tip_m.allFinite() || !s.tip_rest_m.allFinite() || !std::isfinite(s.time_s)) return;
  const bool follows = have_last_ && s.step > last_step_ && s.time_s >= last_time_s_;
  if (have_last_ && !follows) {
    ++f_.resets;
    end_episodes();
    add_event(TimelineKind::kReset, 0, 0, now_ns);
  }
  if (follows) {
    const double dt_s = s.time_s - last_time_s_;
    const Eigen::Vector3d d_mm = (s.tip_m - Eigen::Vector3d(last_tip_[0], last_tip_[1], last_tip_[2])) * 1e3;
    f_.tip_path_mm += d_mm.norm();
    const Eigen::Vector3d beam = xray::c_arm_beam_direction(primary_deg, secondary_deg);
    f_.tip_path_projected_mm += (d_mm - d_mm.dot(beam) * beam).norm();
    f_.tip_path_in_vessels_mm +=
        (s.tip_rest_m - Eigen::Vector3d(last_tip_rest_[0], last_tip_rest_[1], last_tip_rest_[2])).norm() * 1e3;
    if (target_ >= 0 && last_branch_ >= 0 && last_branch_ < static_cast<int>(on_route_.size()) &&
        !on_route_[last_branch_])
      f_.wrong_branch_s += dt_s;
    if (forces_known_ && last_tip_force_n_ > params_.tip_force_threshold_n) f_.tip_force_above_threshold_s += dt_s;
  }
  if (target_ >= 0 && s.tip_branch == target_ && f_.target_reached_s < 0.0) f_.target_reached_s = session_s(now_ns);
  const double force_n = std::isfinite(s.tip_force_n) ? s.tip_force_n : 0.0;
  if (forces_known_) {
    f_.peak_tip_force_n = std::max(f_.peak_tip_force_n, force_n);
    update_episode(force_, force_n > params_.tip_force_risk_n, force_n, s.time_s, now_ns);
  }
  // the wire folded back on itself (a prolapse)
  const double fold_deg = fold_angle_deg(s.wire_nodes_m);
  update_episode(fold_, fold_deg > kProlapseDeg, fold_deg, s.time_s, now_ns);
  // the feed of the last second against the tip's motion through the vessels (a buckling wire
  // stores the feed as a bend or a loop instead of carrying the tip on)
  {
    const FeedSample now{s.time_s, s.insertion_m, s.tip_rest_m};
    const FeedSample* then = nullptr;
    for (int k = 0; k < feed_count_; ++k) {
      const FeedSample& c = feed_samples_[(feed_head_ - 1 - k + 64) % 64];
      if (now.time_s - c.time_s >= 1.0 - 1e-9) {
        then = &c;
        break;
      }
    }
    double stored_mm = 0.0;
    if (then) {
      const double fed_mm = (now.insertion_m - then->insertion_m) * 1e3;
      const double moved_mm = (now.tip_rest_m - then->tip_rest_m).norm() * 1e3;
      if (fed_mm >= kBucklingFeedMm && moved_mm < 0.25 * fed_mm) stored_mm = fed_mm - moved_mm;
    }
    update_episode(feed_, stored_mm > 0.0, stored_mm, s.time_s, now_ns);
    // the ring spans two seconds at any physics rate: a sample every 1/32 s at most
    const bool spaced = feed_count_ == 0 || now.time_s - feed_samples_[(feed_head_ + 63) % 64].time_s >= 1.0 / 32;
    if (spaced) {
      feed_samples_[feed_head_] = now;
      feed_head_ = (feed_head_ + 1) % 64;
      feed_count_ = std::min(feed_count_ + 1, 64);
    }
  }
  // the track: every stride-th state; full, every other point goes and the stride doubles
  if (++track_skip_ >= track_stride_) {
    track_skip_ = 0;
    if (track_count_ == kMaxTrack) {
      for (int i = 0; i < kMaxTrack / 2; ++i) track_[i] = track_[2 * i];
      track_count_ = kMaxTrack / 2;
      track_stride_ *= 2;
    }
    TrackPoint& p = track_[track_count_++];
    p.time_s = session_s(now_ns);
    for (int k = 0; k < 3; ++k) p.tip_mm[k] = static_cast<float>(s.tip_m[k] * 1e3);
    p.tip_force_n = static_cast<float>(forces_known_ ? force_n : 0.0);
    p.heart_phase = static_cast<float>(std::isfinite(s.heart_phase) ? s.heart_phase : 0.0);
    p.off_route = target_ >= 0 && s.tip_branch >= 0 && s.tip_branch < static_cast<int>(on_route_.size()) &&
                  !on_route_[s.tip_branch];
    p.pipeline = pipeline_;
  }
  have_last_ = true;
  last_step_ = s.step;
  last_time_s_ = s.time_s;
  for (int k = 0; k < 3; ++k) {
    last_tip_[k] = s.tip_m[k];
    last_tip_rest_[k] = s.tip_rest_m[k];
  }
  last_branch_ = s.tip_branch;
  last_tip_force_n_ = force_n;
}

void SessionMetrics::figures_without_lists(int64_t now_ns, DebriefFigures* out) const {
  std::lock_guard lock(mutex_);
  DebriefFigures& o = *out;
  // field by field: the strings assigned into their own storage, the lists untouched
  o.procedure_time_s = session_s(now_ns);
  o.fluoro_time_s = f_.fluoro_time_s;
  o.cine_time_s = f_.cine_time_s;
  o.fluoro_pulses = f_.fluoro_pulses;
  o.cine_frames = f_.cine_frames;
  o.cine_runs = f_.cine_runs;
  o.contrast_injections = f_.contrast_injections;
  o.contrast_ml = f_.contrast_ml;
  o.air_kerma_mgy = f_.air_kerma_mgy;
  o.dap_gycm2 = f_.dap_gycm2;
  o.tip_path_mm = f_.tip_path_mm;
  o.tip_path_projected_mm = f_.tip_path_projected_mm;
  o.tip_path_in_vessels_mm = f_.tip_path_in_vessels_mm;
  o.has_target = f_.has_target;
  o.target_branch.assign(f_.target_branch);
  o.wrong_branch_s = f_.wrong_branch_s;
  o.target_reached_s = f_.target_reached_s;
  o.tip_forces_known = f_.tip_forces_known;
  o.peak_tip_force_n = f_.peak_tip_force_n;
  o.tip_force_above_threshold_s = f_.tip_force_above_threshold_s;
  o.force_events = force_.count + (force_.on ? 1 : 0);
  o.prolapse_events = fold_.count + (fold_.on ? 1 : 0);
  o.buckling_events = feed_.count + (feed_.on ? 1 : 0);
  o.wire_states = f_.wire_states;
  o.resets = f_.resets;
  o.timeline_dropped = f_.timeline_dropped;
}

DebriefFigures SessionMetrics::figures(int64_t now_ns) const {
  std::lock_guard lock(mutex_);
  DebriefFigures f = f_;
  f.procedure_time_s = session_s(now_ns);
  f.params = params_;
  f.carm_poses.assign(poses_.begin(), poses_.begin() + pose_count_);
  f.timeline.assign(timeline_.begin(), timeline_.begin() + timeline_count_);
  f.track.assign(track_.begin(), track_.begin() + track_count_);
  f.angiogram = angiogram_;
  // an episode still going on at the end counts
  for (const Episode* e : {&force_, &fold_, &feed_}) {
    if (!e->on) continue;
    if (f.timeline.size() < kMaxTimeline)
      f.timeline.push_back({e->start_s, e->kind, e->peak, last_time_s_ - e->sim_start_s});
    else
      ++f.timeline_dropped;
  }
  f.force_events = force_.count + (force_.on ? 1 : 0);
  f.prolapse_events = fold_.count + (fold_.on ? 1 : 0);
  f.buckling_events = feed_.count + (feed_.on ? 1 : 0);
  std::stable_sort(f.timeline.begin(), f.timeline.end(),
                   [](const TimelineEntry& a, const TimelineEntry& b) { return a.time_s < b.time_s; });
  return f;
}

nlohmann::json to_json(const DebriefFigures& f) {
  using nlohmann::json;
  json poses = json::array();
  for (const CArmUse& p : f.carm_poses)
    poses.push_back({{"primary_deg", p.primary_deg}, {"secondary_deg", p.secondary_deg}, {"beam_s", p.beam_s}});
  json timeline = json::array();
  for (const TimelineEntry& e : f.timeline) {
    json j = {{"time_s", e.time_s}, {"kind", timeline_kind_name(e.kind)}};
    if (e.kind == TimelineKind::kCArm) {
      j["primary_deg"] = e.a;
      j["secondary_deg"] = e.b;
    } else if (e.kind == TimelineKind::kContrast) {
      j["ml"] = e.a;
    } else if (e.kind == TimelineKind::kForceEvent) {
      j["peak_n"] = e.a;
      j["duration_s"] = e.b;
    } else if (e.kind == TimelineKind::kProlapse) {
      j["fold_deg"] = e.a;
      j["duration_s"] = e.b;
    } else if (e.kind == TimelineKind::kBuckling) {
      j["not_taken_up_mm"] = e.a;
      j["duration_s"] = e.b;
    }
    timeline.push_back(std::move(j));
  }
  // the tip's track, thinned to at most kJsonTrackPoints: [session s, x, y, z mm, tip N, off route,
  // heart phase]
  constexpr size_t kJsonTrackPoints = 1000;
  json track = json::array();
  const size_t every = f.track.size() / kJsonTrackPoints + 1;
  for (size_t i = 0; i < f.track.size(); i += every) {
    const TrackPoint& p = f.track[i];
    track.push_back({p.time_s, p.tip_mm[0], p.tip_mm[1], p.tip_mm[2], p.tip_force_n, p.off_route, p.heart_phase});
  }
  const json unknown = nullptr;
  return {
      {"procedure_time_s", f.procedure_time_s},
      {"fluoro_time_s", f.fluoro_time_s},
      {"cine_time_s", f.cine_time_s},
      {"fluoro_pulses", f.fluoro_pulses},
      {"cine_frames", f.cine_frames},
      {"cine_runs", f.cine_runs},
      {"contrast_injections", f.contrast_injections},
      {"contrast_ml", f.contrast_ml},
      {"air_kerma_mgy", f.air_kerma_mgy},
      {"dap_gycm2", f.dap_gycm2},
      {"carm_poses", poses},
      {"tip_path_mm", f.tip_path_mm},
      {"tip_path_projected_mm", f.tip_path_projected_mm},
      {"tip_path_in_vessels_mm", f.tip_path_in_vessels_mm},
      {"target_branch", f.target_branch},
      {"wrong_branch_s", f.has_target ? json(f.wrong_branch_s) : unknown},
      {"target_reached_s", f.has_target && f.target_reached_s >= 0.0 ? json(f.target_reached_s) : unknown},
      // the chain-mail wire has no load response: no force figures rather than zeros
      {"peak_tip_force_n", f.tip_forces_known ? json(f.peak_tip_force_n) : unknown},
      {"tip_force_above_threshold_s", f.tip_forces_known ? json(f.tip_force_above_threshold_s) : unknown},
      {"force_events", f.tip_forces_known ? json(f.force_events) : unknown},
      {"prolapse_events", f.prolapse_events},
      {"buckling_events", f.buckling_events},
      {"wire_states", f.wire_states},
      {"wire_restarts", f.resets},
      {"timeline", timeline},
      {"timeline_dropped", f.timeline_dropped},
      {"tip_track", track},
      {"thresholds",
       {{"tip_force_threshold_n", f.params.tip_force_threshold_n},
        {"tip_force_risk_n", f.params.tip_force_risk_n},
        {"tube_output_ugy_per_mas_at_1m", f.params.tube_output_ugy_per_mas_at_1m},
        {"fluoro_mas_per_pulse", f.params.fluoro_mas_per_pulse},
        {"cine_mas_per_frame", f.params.cine_mas_per_frame}}},
  };
}

std::string human_debrief(const DebriefFigures& f) {
  std::string s = fmt::format(
      "debrief: procedure {:.1f} s, beam {:.1f} s ({} cine run{}), {} pulses + {} cine frames, air kerma {:.2f} mGy, "
      "DAP {:.3f} Gy cm2, contrast {:.1f} ml in {} injection{}\n",
      f.procedure_time_s, f.fluoro_time_s, f.cine_runs, f.cine_runs == 1 ? "" : "s", f.fluoro_pulses, f.cine_frames,
      f.air_kerma_mgy, f.dap_gycm2, f.contrast_ml, f.contrast_injections, f.contrast_injections == 1 ? "" : "s");
  s += fmt::format("         tip path {:.0f} mm ({:.0f} mm across the beam, {:.0f} mm through the vessels), ",
                   f.tip_path_mm, f.tip_path_projected_mm, f.tip_path_in_vessels_mm);
  if (f.has_target)
    s += fmt::format("{:.1f} s off the route to {}{}", f.wrong_branch_s, f.target_branch,
                     f.target_reached_s >= 0.0 ? fmt::format(" (reached at {:.1f} s)", f.target_reached_s)
                                               : std::string(" (not reached)"));
  else
    s += "no target branch";
  if (f.tip_forces_known)
    s += fmt::format(", tip force at most {:.3f} N, {:.1f} s above {} N, {} event{} above {} N", f.peak_tip_force_n,
                     f.tip_force_above_threshold_s, f.params.tip_force_threshold_n, f.force_events,
                     f.force_events == 1 ? "" : "s", f.params.tip_force_risk_n);
  else
    s += ", no tip forces (the chain-mail wire computes none)";
  return s;
}

}  // namespace pcisim::server
