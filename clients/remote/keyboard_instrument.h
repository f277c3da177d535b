#pragma once
// The page's keyboard as an instrument, for use without hardware: arrow keys set an insertion
// and a rotation speed, and a thread publishes instrument_state_t at the bridge's rate, as the
// bridge's scripted device would. One connection owns it at a time. It never fights hardware:
// the server follows the newest sample from any device, so while another device is heard the
// keyboard instrument will not start, and it stops publishing the moment one appears.
// Keys that stop arriving (a page that froze or lost its link) count as released.
#include <atomic>
#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <string>
#include <thread>

namespace pcisim::remote {

struct KeyboardOptions {
  double rate_hz = 1000;
  int32_t device_id = 90;
  double insert_mm_s = 20, rotate_rad_s = 2;  // full speed of a held key
  double max_insertion_mm = 400;
  int64_t key_timeout_ns = 400'000'000;  // no key update for this long: keys released
};

class KeyboardInstrument {
 public:
  // `other_active` says whether another instrument is being heard (asked on the publishing thread)
  KeyboardInstrument(lcm::LCM& lcm, const KeyboardOptions& options, std::function<bool()> other_active);
  ~KeyboardInstrument();

  // owner: a connection id. Start from the wire's insertion and rotation so nothing jumps.
  // Returns "" on success, else why not.
  std::string enable(uint64_t owner, double start_insertion_mm, double start_rotation_rad);
  void disable(uint64_t owner);
  // insert, rotate in [-1, 1] (fractions of full speed); false when `owner` does not own it
  bool set_keys(uint64_t owner, double insert, double rotate, int64_t now_ns);

  uint64_t owner() const { return owner_.load(); }
  bool enabled() const { return owner_.load() != 0; }
  int64_t published() const { return published_.load(); }
  double insertion_mm() const;
  double rotation_rad() const;
  std::string stop_reason() const;  // why it stopped on its own, "" if it did not

 private:
  void run();

  lcm::LCM& lcm_;
  KeyboardOptions options_;
  std::function<bool()> other_active_;
  std::atomic<uint64_t> owner_{0};
  std::atomic<bool> quit_{false};
  std::atomic<int64_t> published_{0};
  mutable std::mutex mutex_;  // guards the motion below
  double insertion_mm_ = 0, rotation_rad_ = 0, insert_ = 0, rotate_ = 0;
  int64_t keys_ns_ = 0;
  std::string stop_reason_;
  std::thread thread_;
};

}  // namespace pcisim::remote
