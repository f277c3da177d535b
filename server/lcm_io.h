#pragma once
// LCM I/O for the control instance: a receive thread (lcm handle is single-threaded) and a send
// thread that drains the haptic ring and the physics snapshots. Bad messages are counted and
// dropped; nothing here can stall the 1 kHz loop.
#include <array>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "pcisim_lcm/force_command_t.hpp"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/probe_state_t.hpp"
#include "pcisim_lcm/session_command_t.hpp"
#include "pcisim_lcm/session_metrics_t.hpp"
#include "pcisim_lcm/sim_status_t.hpp"
#include "pcisim_lcm/wire_state_t.hpp"
#include "protocol/channels.h"
#include "protocol/encoded_publisher.h"
#include "server/debrief/session_metrics.h"
#include "server/session_limits.h"
#include "server/shared_state.h"

namespace pcisim::server {

class LcmIo {
 public:
  // fills the status message in place (the send thread's, kept between calls: a source that
  // keeps its own storage allocates nothing)
  using StatusSource = std::function<void(pcisim_lcm::sim_status_t&)>;
  // a branch's name by index ("" when unknown): a reference, so that a wire state copies it into
  // its message's string without a temporary (a name past 15 characters would allocate each step)
  using BranchNamer = std::function<const std::string&(int)>;

  // the instrument the scene is driven by: the wire's (PCISIM_INSTRUMENT) or the ultrasound
  // probe (PCISIM_PROBE, the soft-tissue scene); the other channel is not subscribed
  enum class Instrument { kWire, kProbe };

  // `lcm` and `limits` must outlive this object; status is called once a second from the send
  // thread. `scene_injection_ml` is what an injection that names no volume injects. `metrics`
  // (optional, outliving this object) gets each wire state published and each injection accepted.
  LcmIo(lcm::LCM& lcm, SharedState& state, SessionLimits& limits, double scene_injection_ml, StatusSource status,
        BranchNamer branch_name, Instrument instrument = Instrument::kWire, SessionMetrics* metrics = nullptr);
  ~LcmIo();

  void start();
  // the receive thread alone (it may wait 20 ms in LCM's handle): the send thread goes on
  // publishing the haptic loop's force commands meanwhile
  void stop_receiving();
  void stop();  // joins both threads; publishes a final zero force command
  void publish_zero_force();
  // the send thread's streams (public for the test that counts their allocations, which calls
  // them before start(); never while the send thread runs): the haptic loop's force commands
  // waiting in the shared queue, and one wire state
  void publish_forces();
  void publish_wire(const physics::WorldSnapshot& s);
  // the status message and, with metrics, the session's figures (once a second from the send
  // thread; public for the same test)
  void publish_status();
  void publish_metrics();

 private:
  void on_instrument(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_session(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_probe(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void request_scene(const std::string& path);
  // volume and rate 0: the scene's; a console command may name its own
  void add_injection(double volume_ml = 0.0, double rate_ml_per_s = 0.0);
  void refuse(const char* what, const std::string& why);
  void rx_loop();
  void tx_loop();

  lcm::LCM& lcm_;
  SharedState& state_;
  SessionLimits& limits_;
  double scene_injection_ml_;
  StatusSource status_;
  BranchNamer branch_name_;
  SessionMetrics* metrics_;
  std::array<lcm::Subscription*, 2> subscriptions_{};
  std::thread rx_, tx_;
  std::atomic<bool> running_{false}, receiving_{false};
  // messages reused every time, encoded into buffers kept between calls (encoded_publisher.h): one
  // for the send thread, one for the zero force of stop() (another thread)
  pcisim_lcm::instrument_state_t instrument_msg_{};
  pcisim_lcm::probe_state_t probe_msg_{};
  double last_probe_depth_m_ = 0.0, probe_rate_m_per_s_ = 0.0;
  int64_t last_probe_us_ = 0;  // the sender's utime of the sample the rate is measured from
  pcisim_lcm::session_command_t session_msg_{};
  pcisim_lcm::force_command_t force_msg_{};
  pcisim_lcm::wire_state_t wire_msg_{};
  pcisim_lcm::sim_status_t status_msg_{};
  pcisim_lcm::session_metrics_t metrics_msg_{};
  DebriefFigures metrics_figures_;  // filled in place each second
  protocol::EncodedPublisher tx_publisher_, zero_publisher_;
  const std::string force_channel_{protocol::kForceChannel}, wire_channel_{protocol::kWireChannel},
      status_channel_{protocol::kStatusChannel}, metrics_channel_{protocol::kMetricsChannel};
  int64_t last_instrument_seq_ = -1;
  int64_t status_seq_ = 0, metrics_seq_ = 0;
  // refusals are logged at most once a second (a flood must not flood the log); the rest counted
  int64_t last_refusal_log_ns_ = INT64_MIN / 2, refusals_unlogged_ = 0;
};

}  // namespace pcisim::server
