#pragma once
// The x-ray thread: while a fluoroscopy (or cine) pedal is down it renders the newest physics
// snapshot at the pulse rate (cine rate during cine) and publishes xray_frame_t on the image LCM
// instance, its own socket, so frames never queue in front of 1 kHz traffic. Only built when
// the scene lists "xray".
#include <lcm/lcm-cpp.hpp>
#include <memory>

#include "anatomy/case/case.h"
#include "pcisim_lcm/xray_frame_t.hpp"
#include "protocol/channels.h"
#include "protocol/encoded_publisher.h"
#include "server/scene/scene.h"
#include "server/debrief/session_metrics.h"
#include "server/shared_state.h"
#include "xray/fluoro/fluoroscopy.h"

namespace pcisim::server {

class XrayLoop {
 public:
  // prepares the projector over the case's CT (or the thorax phantom around its vessels when the
  // case has none); may take a second or two
  // `beat`, when given (vessel_motion with xray.heart_phase_bins > 0), makes the background beat:
  // every phase bin of the initial pose is projected here, before the first pedal press
  XrayLoop(const Scene& scene, const anatomy::Case& anatomy, SharedState& state, lcm::LCM* images,
           const xray::BeatSamples* beat = nullptr);
  void run();  // until state.stop
  // the session's debrief figures: beam time, pulses, pedals and C-arm moves (nullptr: none)
  void set_metrics(SessionMetrics* metrics) { metrics_ = metrics; }
  // one frame of the newest snapshot, published (public for the test that counts its allocations;
  // never while run() runs)
  void render_and_publish(bool cine);

 private:
  void apply_carm_target();
  // a C-arm target waits that apply_carm_target() would move to now
  bool move_due(int64_t now_ns) const;

  XraySpec spec_;
  SharedState& state_;
  lcm::LCM* images_;
  protocol::EncodedPublisher publisher_;  // a frame encoded into a buffer kept between frames
  const std::string channel_{protocol::kXrayChannel};
  std::unique_ptr<xray::FluoroscopyRenderer> renderer_;
  std::vector<xray::ContrastInjection> injections_;  // reserved for SharedState::kMaxInjections
  xray::FluoroFrame frame_;
  pcisim_lcm::xray_frame_t msg_{};
  std::vector<std::string> branch_names_;
  int64_t seq_ = 0;
  int64_t applied_target_seq_ = 0, last_move_ns_ = INT64_MIN / 2, min_move_interval_ns_ = 0;
  int32_t cine_run_ = -1;
  bool was_cine_ = false;
  SessionMetrics* metrics_ = nullptr;
};

}  // namespace pcisim::server
