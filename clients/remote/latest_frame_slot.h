#pragma once
// Hands frames from the LCM thread to the encoder thread, newest wins: a frame the encoder had
// no time for is replaced, never queued. One slot per modality (X-ray, ultrasound), so one never
// replaces the other. Swaps buffers, so no frame is copied.
#include <condition_variable>
#include <cstdint>
#include <mutex>

#include "pcisim_lcm/us_frame_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"

namespace pcisim::remote {

class LatestFrameSlot {
 public:
  enum Taken : int { kNone = 0, kXray = 1, kUltrasound = 2 };  // take()'s answer, a bit each

  // swaps `frame` in; `frame` gets the old buffer back to reuse
  void put(pcisim_lcm::xray_frame_t& frame);
  void put(pcisim_lcm::us_frame_t& frame);
  // waits up to timeout_ms for a frame of either kind; swaps each waiting one into its `out`
  // and says which came (kXray | kUltrasound)
  int take(pcisim_lcm::xray_frame_t& xray_out, pcisim_lcm::us_frame_t& us_out, int timeout_ms);
  void wake();  // shutdown
  int64_t replaced() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  pcisim_lcm::xray_frame_t xray_;
  pcisim_lcm::us_frame_t us_;
  int full_ = kNone;
  bool woken_ = false;
  int64_t replaced_ = 0;
};

}  // namespace pcisim::remote
