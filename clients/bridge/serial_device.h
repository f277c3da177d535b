#pragma once
// An encoder box on a serial port (or a pseudo-terminal): one ASCII line per sample, format in
// docs/serial-protocol.md. Malformed lines are counted and skipped; a port that is unplugged
// (read error or hang-up) or silent for longer than the timeout puts the device in fault.
#include <cstdint>
#include <string>

#include "clients/bridge/instrument_device.h"

namespace pcisim::clients {

struct SerialCalibration {
  double mm_per_count = 0.01;    // insertion encoder
  double rad_per_count = 0.001;  // rotation encoder
  int64_t insertion_zero_counts = 0;
  double min_insertion_mm = 0.0;  // readings are clamped into this range
  double max_insertion_mm = 400.0;
  double silent_timeout_s = 0.05;  // no valid line for this long: fault
};

// throws std::invalid_argument ("serial calibration: ...") for zero or non-finite scales, an
// inverted insertion range or a non-positive timeout; SerialDevice checks its calibration with it
void validate(const SerialCalibration& calibration);

// one parsed line: true when it is a valid sample line
struct EncoderLine {
  int64_t insertion_counts = 0, rotation_counts = 0;
  int32_t buttons = 0;
};
bool parse_encoder_line(const std::string& line, EncoderLine& out);

class SerialDevice : public InstrumentDevice {
 public:
  // opens the port raw and non-blocking (baud applies to a real tty; a pty ignores it); throws
  // std::runtime_error naming the port when it cannot be opened
  SerialDevice(const std::string& port, int baud, const SerialCalibration& calibration);
  ~SerialDevice() override;

  bool read(double t_s, InstrumentReading& out) override;
  std::string describe() const override;

  int64_t lines() const { return lines_; }
  int64_t malformed() const { return malformed_; }
  bool unplugged() const { return unplugged_; }

 private:
  void take(const EncoderLine& e, double t_s);

  std::string port_;
  int fd_ = -1;
  SerialCalibration cal_;
  std::string pending_;  // bytes of an unfinished line (reserved up front)
  InstrumentReading reading_;
  double last_valid_t_s_ = -1;
  double last_insertion_mm_ = 0, last_rotation_rad_ = 0, last_sample_t_s_ = -1;
  int64_t lines_ = 0, malformed_ = 0;
  bool unplugged_ = false;
  bool overlong_ = false;  // the line being read outgrew kMaxLine: counted malformed at its end
  static constexpr size_t kMaxLine = 4000;
};

}  // namespace pcisim::clients
