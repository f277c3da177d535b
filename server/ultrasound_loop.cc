#include "server/ultrasound_loop.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <spdlog/spdlog.h>

#include "protocol/channels.h"
#include "realtime/clock.h"
#include "realtime/deadline_schedule.h"

namespace pcisim::server {

UltrasoundLoop::UltrasoundLoop(const Scene& scene, const anatomy::Case& anatomy,
                               const Eigen::Matrix3Xd& rest_tet_vertices_m, const std::vector<std::array<int, 4>>& tets,
                               SharedState& state, lcm::LCM* images)
    : spec_(*scene.ultrasound), state_(state), images_(images), channel_(protocol::kUltrasoundChannel) {
  if (!anatomy.ct) throw std::invalid_argument("ultrasound: the case has no CT to image");
  // the organ's tissue map, where the case has one, gives each tissue's acoustic properties
  const anatomy::TissueMap* tissue = anatomy.organ && anatomy.organ->tissue ? &*anatomy.organ->tissue : nullptr;
  renderer_ = std::make_unique<ultrasound::BModeRenderer>(*anatomy.ct, spec_.settings, tissue);
  // the CT and the physics share the organ's frame (LPS, mm): rest = the model's tet vertices
  mesh_.rest_mm = rest_tet_vertices_m * 1e3;
  mesh_.current_mm = mesh_.rest_mm;
  mesh_.tets = tets;
  renderer_->set_mesh(mesh_);
  state_.ultrasound_enabled = true;
  // a frame's size is fixed by its pixel count (depth and gain change what is in it)
  msg_.num_bytes = spec_.settings.width_px * spec_.settings.height_px;
  msg_.data.resize(static_cast<size_t>(msg_.num_bytes));
  publisher_.reserve(static_cast<size_t>(msg_.getEncodedSize()));
}

void UltrasoundLoop::render_and_publish() {
  state_.snapshot_for_ultrasound.refresh();
  const physics::WorldSnapshot& snap = state_.snapshot_for_ultrasound.read_slot();
  // before physics' first step there is no probe pose to image from
  if (snap.step == 0) return;
  if (static_cast<Eigen::Index>(snap.tissue_tet_vertices_m.size()) == mesh_.current_mm.cols())
    for (Eigen::Index i = 0; i < mesh_.current_mm.cols(); ++i)
      mesh_.current_mm.col(i) = snap.tissue_tet_vertices_m[static_cast<size_t>(i)] * 1e3;
  ultrasound::ProbePose pose;
  pose.origin_mm = snap.probe_position_m * 1e3;
  pose.lateral = snap.probe_rotation.col(0);
  pose.beam = snap.probe_rotation.col(2);
  // the probe's knobs: its depth (0: the scene's) and its gain on top of the scene's, within
  // the scanner's ranges (the decoder allows a deeper ask than the scanner images)
  const ultrasound::UsSettings& scene = spec_.settings;
  renderer_->set_imaging(
      snap.probe_depth_mm > 0.0 ? std::min(snap.probe_depth_mm, ultrasound::kUsMaxDepthMm) : scene.depth_mm,
      std::clamp(scene.gain_db + snap.probe_gain_db, -ultrasound::kUsMaxGainDb, ultrasound::kUsMaxGainDb));
  const int64_t t0 = realtime::monotonic_ns();
  // one speckle seed for the whole run: the pattern does not flicker from frame to frame
  image_ = &renderer_->render(pose, spec_.speckle_seed, &mesh_);
  state_.ultrasound_render_ns.record(realtime::monotonic_ns() - t0);
  state_.ultrasound_frames.fetch_add(1, std::memory_order_relaxed);
  if (!images_) return;

  const ultrasound::UsSettings& s = renderer_->settings();  // the depth and gain imaged
  auto& m = msg_;
  m.utime = realtime::monotonic_us();
  m.seq = seq_++;
  m.width = image_->width;
  m.height = image_->height;
  m.pixel_format = pcisim_lcm::us_frame_t::FORMAT_GRAY8;
  m.geometry = s.geometry == ultrasound::ProbeGeometry::kCurvilinear ? pcisim_lcm::us_frame_t::GEOMETRY_CURVILINEAR
                                                                     : pcisim_lcm::us_frame_t::GEOMETRY_LINEAR;
  m.depth_mm = s.depth_mm;
  m.width_mm = s.width_mm;
  m.fan_angle_deg = s.fan_angle_deg;
  m.radius_of_curvature_mm = s.radius_of_curvature_mm;
  m.gain_db = s.gain_db;
  m.frequency_mhz = s.frequency_mhz;
  for (int k = 0; k < 3; ++k) {
    m.origin_mm[k] = pose.origin_mm[k];
    m.beam[k] = pose.beam[k];
    m.lateral[k] = pose.lateral[k];
    m.probe_force_n[k] = snap.probe_force_n[k];
  }
  m.sim_time_s = snap.time_s;
  m.num_bytes = static_cast<int32_t>(image_->pixels.size());
  m.data.resize(image_->pixels.size());
  std::memcpy(m.data.data(), image_->pixels.data(), m.data.size());
  publisher_.publish(*images_, channel_, m);
}

void UltrasoundLoop::run() {
  realtime::DeadlineSchedule schedule(realtime::monotonic_ns(),
                                      static_cast<int64_t>(std::llround(1e9 / spec_.frame_rate_hz)));
  while (!state_.stop.load(std::memory_order_relaxed)) {
    realtime::sleep_until_ns(schedule.deadline_ns());
    // a frame that cannot be drawn (the GPU renderer's CUDA failing) ends the ultrasound, said
    // once, not the server: the physics and the force go on
    try {
      render_and_publish();
    } catch (const std::exception& e) {
      spdlog::error("ultrasound: no more frames: {}", e.what());
      return;
    }
    schedule.complete(realtime::monotonic_ns());
  }
}

}  // namespace pcisim::server
