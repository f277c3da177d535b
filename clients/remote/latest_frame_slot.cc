#include "clients/remote/latest_frame_slot.h"

#include <chrono>
#include <utility>

namespace pcisim::remote {

void LatestFrameSlot::put(pcisim_lcm::xray_frame_t& frame) {
  {
    std::lock_guard lock(mutex_);
    if (full_ & kXray) ++replaced_;
    std::swap(xray_, frame);
    full_ |= kXray;
  }
  cv_.notify_one();
}

void LatestFrameSlot::put(pcisim_lcm::us_frame_t& frame) {
  {
    std::lock_guard lock(mutex_);
    if (full_ & kUltrasound) ++replaced_;
    std::swap(us_, frame);
    full_ |= kUltrasound;
  }
  cv_.notify_one();
}

int LatestFrameSlot::take(pcisim_lcm::xray_frame_t& xray_out, pcisim_lcm::us_frame_t& us_out, int timeout_ms) {
  std::unique_lock lock(mutex_);
  cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [&] { return full_ != kNone || woken_; });
  woken_ = false;
  const int taken = full_;
  if (taken & kXray) std::swap(xray_, xray_out);
  if (taken & kUltrasound) std::swap(us_, us_out);
  full_ = kNone;
  return taken;
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
