#pragma once
// An instrument box simulated on a pseudo-terminal (tests, scripts/main-job, pcisim-box-sim): it
// sends a trainee script's motion as encoder lines ("E ...", docs/serial-protocol.md) and applies
// the force lines it reads back ("F ...") with the box's watchdog: a line's force holds until the
// next, and drops to zero once no valid line came for kBoxWatchdogS. The bridge opens port().
#include <cstdint>
#include <string>
#include <vector>

#include "clients/bridge/force_line.h"
#include "clients/bridge/serial_device.h"
#include "clients/bridge/trainee_script.h"

namespace pcisim::clients {

struct BoxForceSample {
  double t_s = 0.0;  // when the box read it (its own clock)
  ForceLine line;
};

class BoxSimulator {
 public:
  // opens a pseudo-terminal (throws std::runtime_error when it cannot); counts follow `calibration`
  // (the bridge must be given the same); keeps at most `max_log` force lines
  BoxSimulator(TraineeScript script, const SerialCalibration& calibration, int64_t max_log = 1'000'000);
  ~BoxSimulator();
  BoxSimulator(const BoxSimulator&) = delete;
  BoxSimulator& operator=(const BoxSimulator&) = delete;

  const std::string& port() const { return port_; }
  // the box at time t_s (its clock): sends the script's sample, then reads what came back
  void step(double t_s);
  // reads what came back without sending (a box whose encoders went silent)
  void listen(double t_s) { read_forces(t_s); }
  // what the actuators apply at t_s, after the watchdog (zero before any line)
  double applied_axial_n(double t_s) const;
  double applied_torque_nmm(double t_s) const;
  bool watchdog_tripped(double t_s) const;

  const std::vector<BoxForceSample>& log() const { return log_; }
  int64_t lines_sent() const { return sent_; }
  int64_t force_lines() const { return received_; }
  int64_t malformed() const { return malformed_; }
  // writes the log as CSV: t_s, axial_mN, torque_uNm, seq
  void write_csv(const std::string& path) const;

 private:
  void read_forces(double t_s);

  TraineeScript script_;
  SerialCalibration cal_;
  int master_ = -1, slave_ = -1;  // the slave stays open so the port exists before the bridge opens it
  std::string port_;
  std::string pending_;  // a force line being read
  std::string out_;      // the tail of an encoder line the pty took in part
  std::vector<BoxForceSample> log_;
  int64_t max_log_ = 0, sent_ = 0, received_ = 0, malformed_ = 0;
  ForceLine last_{};
  double last_line_t_s_ = -1.0;
};

}  // namespace pcisim::clients
