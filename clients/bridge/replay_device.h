#pragma once
// Plays back the instrument stream of a session recorded with lcm-logger: at 1x, faster or
// slower (speed), or stepped (one recorded sample per read, whatever the clock says).
#include <cstdint>
#include <string>
#include <vector>

#include "clients/bridge/instrument_device.h"

namespace pcisim::clients {

class ReplayDevice : public InstrumentDevice {
 public:
  // speed > 0 scales time; speed == 0 steps. Throws std::runtime_error naming the file when
  // it cannot be read or holds no instrument samples on `channel`.
  ReplayDevice(const std::string& log_path, double speed, const std::string& channel);

  bool read(double t_s, InstrumentReading& out) override;
  bool finished(double t_s) const override;
  std::string describe() const override;
  size_t samples() const { return samples_.size(); }
  int64_t skipped_bad() const { return skipped_bad_; }

 private:
  struct Sample {
    double t_s;  // since the first recorded sample
    InstrumentReading reading;
    bool fault;
  };
  std::string path_;
  double speed_;
  std::vector<Sample> samples_;
  size_t next_ = 0;
  int64_t skipped_bad_ = 0;
};

}  // namespace pcisim::clients
