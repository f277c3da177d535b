#include "clients/capture/capture_sink.h"

#include <spdlog/spdlog.h>

#include "protocol/message_checks.h"

namespace pcisim::clients {

void CaptureSink::on_frame(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  if (done()) return;
  if (!protocol::decode_checked(*rbuf, frame_)) {
    ++bad_;
    return;
  }
  if (only_while_pedal_ && !pedal_) {
    ++skipped_;
    return;
  }
  try {
    const std::string path = writer_.write(frame_);
    if (writer_.written_xray() % 30 == 1)
      spdlog::info("capture: {} X-ray frames, latest {}", writer_.written_xray(), path);
  } catch (const std::exception& e) {
    error_ = e.what();  // stop: what is written stays intact
  }
}

void CaptureSink::on_ultrasound(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  if (done()) return;
  if (!protocol::decode_checked(*rbuf, us_frame_)) {
    ++bad_ultrasound_;
    return;
  }
  try {
    const std::string path = writer_.write(us_frame_);
    if (writer_.written_ultrasound() % 30 == 1)
      spdlog::info("capture: {} ultrasound frames, latest {}", writer_.written_ultrasound(), path);
  } catch (const std::exception& e) {
    error_ = e.what();
  }
}

void CaptureSink::on_instrument(const lcm::ReceiveBuffer* rbuf, const std::string&) {
  using I = pcisim_lcm::instrument_state_t;
  if (!protocol::decode_checked(*rbuf, instrument_)) {
    bad_instrument_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  pedal_ = (instrument_.buttons & (int{I::BUTTON_FLUORO_PEDAL} | int{I::BUTTON_CINE_PEDAL})) != 0;
}

}  // namespace pcisim::clients
