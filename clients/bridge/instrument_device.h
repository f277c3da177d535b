#pragma once
// Where the bridge's instrument readings come from: a trainee script, a recorded session or a
// serial encoder box. The bridge polls read() at its publish rate.
#include <cstdint>
#include <string>

#include "clients/bridge/force_line.h"
#include "clients/bridge/trainee_script.h"

namespace pcisim::clients {

class InstrumentDevice {
 public:
  virtual ~InstrumentDevice() = default;

  // the reading at t_s seconds since the bridge started; false when the device is in fault
  // (unplugged, silent, ...) and `out` must not be used
  virtual bool read(double t_s, InstrumentReading& out) = 0;
  // true once the device has nothing more to give (a replay that reached its end)
  virtual bool finished(double t_s) const { return t_s < 0; }
  // hands the device this tick's force set-point (tick number `seq`); false when nothing reached
  // it (a device with no actuator, or a line the port would not take). Called every tick, after
  // read(), with zero in any fault (force_gate.h); must not block or allocate
  virtual bool render(const ForceSetpoint& /*force*/, int64_t /*seq*/) { return false; }
  virtual std::string describe() const = 0;
};

class ScriptedDevice : public InstrumentDevice {
 public:
  explicit ScriptedDevice(TraineeScript script) : script_(std::move(script)) {}
  bool read(double t_s, InstrumentReading& out) override {
    out = script_.sample(t_s);
    return true;
  }
  std::string describe() const override;

 private:
  TraineeScript script_;
};

}  // namespace pcisim::clients
