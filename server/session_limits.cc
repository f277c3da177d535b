#include "server/session_limits.h"

#include <cmath>

namespace pcisim::server {

namespace {
// true when at least interval_s has passed since last_ns (never, the first time)
bool interval_passed(int64_t now_ns, int64_t last_ns, double interval_s) {
  return last_ns == INT64_MIN || static_cast<double>(now_ns - last_ns) >= interval_s * 1e9;
}
}  // namespace

bool SessionLimits::allow_reset(int64_t now_ns) {
  if (!interval_passed(now_ns, last_reset_ns_, params_.min_reset_interval_s)) {
    resets_refused_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  last_reset_ns_ = now_ns;
  return true;
}

bool SessionLimits::allow_scene_load(int64_t now_ns) {
  if (!interval_passed(now_ns, last_load_ns_, params_.min_scene_load_interval_s)) {
    scene_loads_refused_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  return true;
}

bool SessionLimits::allow_injection(int64_t now_ns, double volume_ml) {
  // the n-th newest injection must be a minute old before another may start
  const int n = params_.max_injections_per_min;
  const int64_t booked = injections_.load(std::memory_order_relaxed);
  const bool rate_ok =
      n > 0 && (booked < n || now_ns - injection_ns_[(ring_next_ - n + kWindow) % kWindow] >= 60'000'000'000);
  const bool volume_ok = std::isfinite(volume_ml) && contrast_ml() + volume_ml <= params_.max_contrast_ml + 1e-9;
  if (!rate_ok || !volume_ok) {
    injections_refused_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  injection_ns_[ring_next_] = now_ns;
  ring_next_ = (ring_next_ + 1) % kWindow;
  injections_.fetch_add(1, std::memory_order_relaxed);
  contrast_ml_.store(contrast_ml() + volume_ml, std::memory_order_relaxed);
  return true;
}

}  // namespace pcisim::server
