#pragma once
// The capture's LCM side: X-ray and ultrasound frames off the image bus into the frame writer, the
// instrument's pedals off the control bus (for --only-while-pedal, which holds back X-ray frames
// only: no pedal drives the ultrasound probe). Every message decodes through the one checked
// path; a malformed one is counted, never written, never fatal.
#include <atomic>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>

#include "clients/capture/frame_writer.h"
#include "pcisim_lcm/instrument_state_t.hpp"
#include "pcisim_lcm/us_frame_t.hpp"
#include "pcisim_lcm/xray_frame_t.hpp"

namespace pcisim::clients {

class CaptureSink {
 public:
  // max_frames 0: no limit; only_while_pedal: keep frames only while an instrument pedal is down
  CaptureSink(FrameWriter& writer, int64_t max_frames, bool only_while_pedal)
      : writer_(writer), max_frames_(max_frames), only_while_pedal_(only_while_pedal) {}

  // both frame handlers run on the image bus's thread
  void on_frame(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_ultrasound(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_instrument(const lcm::ReceiveBuffer* rbuf, const std::string& channel);

  bool done() const { return !error_.empty() || (max_frames_ > 0 && writer_.written() >= max_frames_); }
  const std::string& error() const { return error_; }  // why writing stopped (a full disk, say)
  int64_t bad() const { return bad_; }                 // undecodable X-ray frames
  int64_t bad_ultrasound() const { return bad_ultrasound_; }
  int64_t bad_instrument() const { return bad_instrument_; }
  int64_t skipped() const { return skipped_; }  // good X-ray frames dropped with the pedal up

 private:
  FrameWriter& writer_;
  int64_t max_frames_;
  bool only_while_pedal_;
  std::atomic<bool> pedal_{false};  // written by the control thread, read by the image thread
  int64_t bad_ = 0, bad_ultrasound_ = 0, skipped_ = 0;
  std::atomic<int64_t> bad_instrument_{0};
  std::string error_;
  pcisim_lcm::xray_frame_t frame_;
  pcisim_lcm::us_frame_t us_frame_;
  pcisim_lcm::instrument_state_t instrument_;
};

}  // namespace pcisim::clients
