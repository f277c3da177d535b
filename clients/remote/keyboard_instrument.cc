#include "clients/remote/keyboard_instrument.h"

#include <algorithm>
#include <cmath>

#include "pcisim_lcm/instrument_state_t.hpp"
#include "protocol/channels.h"
#include "realtime/clock.h"

namespace pcisim::remote {

using realtime::monotonic_ns;

KeyboardInstrument::KeyboardInstrument(lcm::LCM& lcm, const KeyboardOptions& options,
                                       std::function<bool()> other_active)
    : lcm_(lcm), options_(options), other_active_(std::move(other_active)) {
  thread_ = std::thread([this] { run(); });
}

KeyboardInstrument::~KeyboardInstrument() {
  quit_ = true;
  thread_.join();
}

std::string KeyboardInstrument::enable(uint64_t owner, double start_insertion_mm, double start_rotation_rad) {
  if (owner == 0) return "no owner";
  if (other_active_ && other_active_()) return "another instrument is active; the keyboard instrument stays off";
  std::lock_guard lock(mutex_);  // the publishing thread sees owner and motion change together
  uint64_t expected = 0;
  if (!owner_.compare_exchange_strong(expected, owner) && expected != owner)
    return "another page already drives the keyboard instrument";
  if (expected == owner) return "";
  insertion_mm_ =
      std::clamp(std::isfinite(start_insertion_mm) ? start_insertion_mm : 0.0, 0.0, options_.max_insertion_mm);
  rotation_rad_ = std::isfinite(start_rotation_rad) ? start_rotation_rad : 0.0;
  insert_ = rotate_ = 0;
  keys_ns_ = monotonic_ns();
  stop_reason_.clear();
  return "";
}

void KeyboardInstrument::disable(uint64_t owner) {
  uint64_t expected = owner;
  owner_.compare_exchange_strong(expected, 0);
}

bool KeyboardInstrument::set_keys(uint64_t owner, double insert, double rotate, int64_t now_ns) {
  if (owner == 0 || owner_.load() != owner) return false;
  std::lock_guard lock(mutex_);
  insert_ = std::isfinite(insert) ? std::clamp(insert, -1.0, 1.0) : 0.0;
  rotate_ = std::isfinite(rotate) ? std::clamp(rotate, -1.0, 1.0) : 0.0;
  keys_ns_ = now_ns;
  return true;
}

double KeyboardInstrument::insertion_mm() const {
  std::lock_guard lock(mutex_);
  return insertion_mm_;
}

double KeyboardInstrument::rotation_rad() const {
  std::lock_guard lock(mutex_);
  return rotation_rad_;
}

std::string KeyboardInstrument::stop_reason() const {
  std::lock_guard lock(mutex_);
  return stop_reason_;
}

void KeyboardInstrument::run() {
  const auto period_ns = static_cast<int64_t>(1e9 / options_.rate_hz);
  pcisim_lcm::instrument_state_t m{};
  m.device_id = options_.device_id;
  m.status = pcisim_lcm::instrument_state_t::STATUS_OK;
  int64_t seq = 0, next_ns = monotonic_ns(), last_ns = next_ns;
  while (!quit_) {
    next_ns += period_ns;
    const int64_t now_ns = monotonic_ns();
    if (next_ns < now_ns) next_ns = now_ns + period_ns;  // late: skip ahead, no burst of catch-up samples
    const double dt_s = (now_ns - last_ns) * 1e-9;
    last_ns = now_ns;
    if (owner_.load() == 0) {
      realtime::sleep_until_ns(now_ns + 20'000'000);  // idle: no 1 kHz wake-ups for nothing
      next_ns = last_ns = monotonic_ns();
      continue;
    }
    {
      if (other_active_ && other_active_()) {
        // hardware appeared: it wins, and the page hears why its instrument went off
        std::lock_guard lock(mutex_);
        stop_reason_ = "another instrument became active";
        owner_ = 0;
      } else {
        std::lock_guard lock(mutex_);
        if (now_ns - keys_ns_ > options_.key_timeout_ns) insert_ = rotate_ = 0;
        const double v = insert_ * options_.insert_mm_s, w = rotate_ * options_.rotate_rad_s;
        const double before = insertion_mm_;
        insertion_mm_ = std::clamp(insertion_mm_ + v * dt_s, 0.0, options_.max_insertion_mm);
        rotation_rad_ += w * dt_s;
        m.utime = now_ns / 1000;
        m.seq = seq++;
        m.insertion_mm = insertion_mm_;
        m.rotation_rad = rotation_rad_;
        m.insertion_rate_mm_s = dt_s > 0 && insertion_mm_ != before ? v : 0.0;
        m.rotation_rate_rad_s = w;
      }
      if (owner_.load() != 0) {
        lcm_.publish(protocol::kInstrumentChannel, &m);
        ++published_;
      }
    }
    realtime::sleep_until_ns(next_ns);
  }
}

}  // namespace pcisim::remote
