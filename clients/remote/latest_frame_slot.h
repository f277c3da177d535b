#pragma once
// Hands frames from the LCM thread to the encoder thread, newest wins: a frame the encoder had
// no time for is replaced, never queued. Swaps buffers, so no frame is copied.
#include <condition_variable>
#include <cstdint>
#include <mutex>

#include "pcisim_lcm/xray_frame_t.hpp"

namespace pcisim::remote {

class LatestFrameSlot {
 public:
  // swaps `frame` in; `frame` gets the old buffer back to reuse
  void put(pcisim_lcm::xray_frame_t& frame);
  // waits up to timeout_ms for a frame; swaps it into `out`
  bool take(pcisim_lcm::xray_frame_t& out, int timeout_ms);
  void wake();  // shutdown
  int64_t replaced() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  pcisim_lcm::xray_frame_t frame_;
  bool full_ = false, woken_ = false;
  int64_t replaced_ = 0;
};

}  // namespace pcisim::remote
