#pragma once
// What a trainer's screen reports, gathered from the server's traffic: the wire, the C-arm, the
// pedals, and the cath-lab metrics (fluoroscopy time, contrast used). The server reports those
// two metrics once a second in sim_status_t (since it started, so a gateway that joins late shows
// them whole); between reports, and before the first, they are also accumulated here from what
// crosses the bus: pedal time from session commands and the instrument's pedal bits, contrast
// from injections (commands and the instrument's contrast button) times the scene's volume per
// injection. Shown: the server's figure plus what the bus added since it. Fed by the LCM threads,
// read by the web thread.
#include <cstdint>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>

#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/session_command_t.hpp"
#include "pcisim_lcm/session_metrics_t.hpp"
#include "pcisim_lcm/sim_status_t.hpp"
#include "pcisim_lcm/wire_state_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"

namespace pcisim::remote {

struct TrackerOptions {
  double injection_ml = 8;                     // per injection seen on the bus before a status reports it
  int max_injections = 256;                    // the server keeps this many
  int32_t own_device_id = 90;                  // the keyboard instrument's samples are ours, not "another instrument"
  int64_t instrument_active_ns = 200'000'000;  // an instrument heard within this is active
  int64_t server_alive_ns = 3'000'000'000;     // a status within this: the server runs
};

class SessionTracker {
 public:
  explicit SessionTracker(const TrackerOptions& options = {}) : options_(options) {}

  void on_wire(const pcisim_lcm::wire_state_t& m, int64_t now_ns);
  void on_status(const pcisim_lcm::sim_status_t& m, int64_t now_ns);
  void on_session(const pcisim_lcm::session_command_t& m, int64_t now_ns);
  void on_instrument(const pcisim_lcm::instrument_state_t& m, int64_t now_ns);
  void on_frame(const pcisim_lcm::xray_frame_t& m, int64_t now_ns);
  // the server's debrief so far (session_metrics_t, once a second): shown with the status
  void on_metrics(const pcisim_lcm::session_metrics_t& m, int64_t now_ns);

  nlohmann::json state_json(int64_t now_ns) const;   // {"type":"state", ...}
  nlohmann::json status_json(int64_t now_ns) const;  // {"type":"status", ...}; null before the first
  // the status's "debrief": the latest session_metrics_t (null before the first)
  nlohmann::json debrief_json() const;
  int64_t status_seq() const;  // changes when a new sim_status_t arrives

  double fluoro_time_s(int64_t now_ns) const;
  int injections() const;
  bool other_instrument_active(int64_t now_ns) const;
  // where the wire is now, so a keyboard instrument can start there instead of jumping
  std::optional<std::pair<double, double>> wire_insertion_rotation() const;

 private:
  void update_beam(int64_t now_ns);           // call with the lock held after any pedal change
  double local_beam_s(int64_t now_ns) const;  // lock held
  void add_injection(double volume_ml);

  TrackerOptions options_;
  mutable std::mutex mutex_;
  std::optional<pcisim_lcm::wire_state_t> wire_;
  std::optional<pcisim_lcm::sim_status_t> status_;
  std::optional<pcisim_lcm::session_metrics_t> metrics_;
  int64_t status_ns_ = 0, wire_ns_ = 0, frame_ns_ = 0, frames_ = 0;
  std::optional<double> primary_deg_, secondary_deg_;
  bool console_fluoro_ = false, console_cine_ = false, instrument_fluoro_ = false, instrument_cine_ = false;
  bool contrast_button_ = false;
  bool beam_on_ = false;
  int64_t beam_since_ns_ = 0, beam_total_ns_ = 0;
  int injections_ = 0;
  double injected_ml_ = 0;  // the volumes of the injections counted here
  // the local counts when the last sim_status_t arrived: what the bus added since is on top
  double beam_s_at_status_ = 0;
  int injections_at_status_ = 0;
  double injected_ml_at_status_ = 0;
  int64_t other_instrument_ns_ = 0;
  int32_t other_device_id_ = -1;
  double frame_sim_time_s_ = 0;
  bool frame_cine_ = false;
  int64_t frame_seq_ = -1;
};

}  // namespace pcisim::remote
