#pragma once
// The bounds a cath lab puts on a session's console commands, kept across scene reloads (one
// object per server process, outliving each pipeline). Only the LCM receive thread decides; the
// counters are read by the status sender.
#include <atomic>
#include <cstdint>

namespace pcisim::server {

// scene key "session"; ranges in scene_loader.cc
struct SessionLimitParams {
  double min_reset_interval_s = 5.0;        // a reset rebuilds the world (seconds of work)
  double min_scene_load_interval_s = 10.0;  // a load rebuilds everything
  int max_injections_per_min = 6;           // contrast injections in any 60 s window
  double max_contrast_ml = 300.0;           // contrast over the whole session
  double min_carm_move_interval_s = 0.5;    // a C-arm move re-projects the background; newer targets wait
};

class SessionLimits {
 public:
  // the running scene's limits; the history (times, totals, counts) stays
  void configure(const SessionLimitParams& p) { params_ = p; }
  const SessionLimitParams& params() const { return params_; }

  // each true when the command may go ahead, and then books it; false counts a refusal
  bool allow_reset(int64_t now_ns);
  bool allow_scene_load(int64_t now_ns);  // books nothing: a load counts once accepted
  void book_scene_load(int64_t now_ns) { last_load_ns_ = now_ns; }
  bool allow_injection(int64_t now_ns, double volume_ml);

  // a scene that parsed and was refused when built, or did not parse
  void count_scene_rejected() { scenes_rejected_.fetch_add(1, std::memory_order_relaxed); }
  void count_injection_refused() { injections_refused_.fetch_add(1, std::memory_order_relaxed); }

  int64_t resets_refused() const { return resets_refused_.load(std::memory_order_relaxed); }
  int64_t scene_loads_refused() const { return scene_loads_refused_.load(std::memory_order_relaxed); }
  int64_t injections_refused() const { return injections_refused_.load(std::memory_order_relaxed); }
  int64_t scenes_rejected() const { return scenes_rejected_.load(std::memory_order_relaxed); }
  int64_t injections() const { return injections_.load(std::memory_order_relaxed); }
  double contrast_ml() const { return contrast_ml_.load(std::memory_order_relaxed); }

 private:
  static constexpr int kWindow = 64;  // the per-minute limit's upper bound
  SessionLimitParams params_;
  int64_t last_reset_ns_ = INT64_MIN, last_load_ns_ = INT64_MIN;
  int64_t injection_ns_[kWindow] = {};  // ring of the newest injection times
  int ring_next_ = 0;
  std::atomic<int64_t> resets_refused_{0}, scene_loads_refused_{0}, injections_refused_{0}, scenes_rejected_{0};
  std::atomic<int64_t> injections_{0};
  std::atomic<double> contrast_ml_{0.0};
};

}  // namespace pcisim::server
