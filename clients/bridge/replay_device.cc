#include "clients/bridge/replay_device.h"

#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>
#include <stdexcept>

#include "pcisim_lcm/instrument_state_t.hpp"
#include "protocol/message_checks.h"

namespace pcisim::clients {

ReplayDevice::ReplayDevice(const std::string& log_path, double speed, const std::string& channel)
    : path_(log_path), speed_(speed) {
  if (!(speed >= 0)) throw std::runtime_error(fmt::format("replay speed must be >= 0, got {}", speed));
  lcm::LogFile log(log_path, "r");
  if (!log.good()) throw std::runtime_error(fmt::format("{}: cannot read the LCM log", log_path));
  int64_t first_utime = -1;
  pcisim_lcm::instrument_state_t m;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != channel) continue;
    if (!protocol::decode_checked(e->data, e->datalen, m)) {
      ++skipped_bad_;
      continue;
    }
    if (first_utime < 0) first_utime = e->timestamp;
    Sample s;
    s.t_s = (e->timestamp - first_utime) * 1e-6;  // the logger's receive clock
    s.reading = {m.insertion_mm, m.rotation_rad, m.insertion_rate_mm_s, m.rotation_rate_rad_s, m.buttons};
    s.fault = m.status == pcisim_lcm::instrument_state_t::STATUS_FAULT;
    samples_.push_back(s);
  }
  if (samples_.empty())
    throw std::runtime_error(fmt::format("{}: no instrument_state_t samples on channel {}", log_path, channel));
}

bool ReplayDevice::read(double t_s, InstrumentReading& out) {
  if (speed_ == 0) {
    next_ = std::min(next_ + 1, samples_.size());
  } else {
    const double log_t = t_s * speed_;
    while (next_ < samples_.size() && samples_[next_].t_s <= log_t) ++next_;
  }
  if (next_ == 0) {
    out = samples_.front().reading;
    return !samples_.front().fault;
  }
  const Sample& s = samples_[next_ - 1];
  out = s.reading;
  return !s.fault;
}

bool ReplayDevice::finished(double t_s) const {
  if (speed_ == 0) return next_ >= samples_.size();
  return t_s * speed_ > samples_.back().t_s;
}

std::string ReplayDevice::describe() const {
  return fmt::format("replay of {} ({} samples, {:.1f} s, {})", path_, samples_.size(), samples_.back().t_s,
                     speed_ == 0 ? std::string("stepped") : fmt::format("{}x", speed_));
}

}  // namespace pcisim::clients
