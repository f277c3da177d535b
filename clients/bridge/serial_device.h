#pragma once
// An encoder box on a serial port (or a pseudo-terminal): one ASCII line per sample, format in
// docs/serial-protocol.md. Malformed lines are counted and skipped; a port that is unplugged
// (read error or hang-up) or silent for longer than the timeout puts the device in fault. The
// bridge's force goes back on the same port, one line per tick (force_line.h).
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
  // no valid line for this long: fault (and zero force, within the 50 ms a fault may take to
  // reach the hand, docs/serial-protocol.md)
  double silent_timeout_s = 0.03;
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
  // writes the force line (force_line.h) without blocking: a line the port takes in part is
  // finished before the next; while the port takes nothing, lines are dropped (counted)
  bool render(const ForceSetpoint& force, int64_t seq) override;
  std::string describe() const override;

  int64_t force_lines() const { return force_lines_; }
  int64_t force_lines_dropped() const { return force_lines_dropped_; }
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
  // the force side: the unwritten tail of the last line
  char out_[kForceLineMaxBytes + 1] = {};  // a line, and a newline before it after a flush
  size_t out_begin_ = 0, out_end_ = 0;
  int64_t force_lines_ = 0, force_lines_dropped_ = 0;
  static constexpr size_t kMaxLine = 4000;
};

}  // namespace pcisim::clients
