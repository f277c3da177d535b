#pragma once
// A force-feedback wheel made by the kernel's uinput module, for the evdev device's tests (no
// hardware): two absolute axes (ABS_X the wheel, -32768 ... 32767; ABS_Y a pedal, 0 ... 1023),
// three buttons (BTN_0 ... BTN_2) and FF_CONSTANT, FF_SPRING, FF_GAIN and FF_AUTOCENTER with room
// for 4 effects. A thread answers the kernel's effect uploads and erasures (uinput hands them to
// the device's maker) and records every effect, play, stop and setting the device is sent.
#include <linux/input.h>

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace pcisim::clients::testing {

struct FfRecord {
  enum Kind { kUpload, kErase, kPlay, kStop, kGain, kAutocenter } kind;
  int64_t t_ns;       // monotonic
  int id = -1;        // the effect's
  int16_t level = 0;  // an upload's constant level
  int16_t coeff = 0;  // a spring upload's coefficient (right; -1 when left differs) and centre
  int16_t centre = 0;
  uint16_t type = 0;  // an upload's effect type
  int32_t value = 0;  // a setting's value
};

class UinputWheel {
 public:
  // "" when /dev/uinput can be opened for writing; otherwise why not (the test's skip message)
  static std::string unavailable();
  // creates the device; throws std::runtime_error saying which step failed
  explicit UinputWheel(const std::string& name = "pcisim test wheel");
  ~UinputWheel();  // destroys the device (an open evdev sees ENODEV)
  UinputWheel(const UinputWheel&) = delete;
  UinputWheel& operator=(const UinputWheel&) = delete;

  // the evdev node (/dev/input/eventN, or a node made beside it where /dev has none)
  const std::string& event_path() const { return event_path_; }
  void move(int abs_code, int32_t value);  // an axis event and its report
  void press(int key_code, bool down);
  void unplug();  // destroys the device now
  std::vector<FfRecord> records() const;

 private:
  void serve();
  int fd_ = -1;
  std::string event_path_, made_node_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  mutable std::mutex mutex_;
  std::vector<FfRecord> records_;
};

}  // namespace pcisim::clients::testing
