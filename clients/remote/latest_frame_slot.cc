#include "clients/remote/latest_frame_slot.h"

#include <chrono>
#include <utility>

namespace pcisim::remote {

void LatestFrameSlot::put(pcisim_lcm::xray_frame_t& frame) {
  {
    std::lock_guard lock(mutex_);
    if (full_) ++replaced_;
    std::swap(frame_, frame);
    full_ = true;
  }
  cv_.notify_one();
}

bool LatestFrameSlot::take(pcisim_lcm::xray_frame_t& out, int timeout_ms) {
  std::unique_lock lock(mutex_);
  cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [&] { return full_ || woken_; });
  woken_ = false;
  if (!full_) return false;
  std::swap(frame_, out);
  full_ = false;
  return true;
}

void LatestFrameSlot::wake() {
  {
    std::lock_guard lock(mutex_);
    woken_ = true;
  }
  cv_.notify_all();
}

int64_t LatestFrameSlot::replaced() const {
  std::lock_guard lock(mutex_);
  return replaced_;
}

}  // namespace pcisim::remote
