#include "clients/bridge/box_simulator.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace pcisim::clients {

BoxSimulator::BoxSimulator(TraineeScript script, const SerialCalibration& calibration, int64_t max_log)
    : script_(std::move(script)), cal_(calibration), max_log_(max_log) {
  validate(calibration);
  char name[256] = {};
  if (openpty(&master_, &slave_, name, nullptr, nullptr) != 0)
    throw std::runtime_error(fmt::format("box simulator: cannot open a pseudo-terminal: {}", std::strerror(errno)));
  termios tio{};
  if (tcgetattr(slave_, &tio) == 0) {
    cfmakeraw(&tio);
    tcsetattr(slave_, TCSANOW, &tio);
  }
  fcntl(master_, F_SETFL, fcntl(master_, F_GETFL) | O_NONBLOCK);
  port_ = name;
  pending_.reserve(256);
  out_.reserve(128);
  log_.reserve(static_cast<size_t>(std::min<int64_t>(max_log_, 1 << 16)));
}

BoxSimulator::~BoxSimulator() {
  if (master_ >= 0) ::close(master_);
  if (slave_ >= 0) ::close(slave_);
}

void BoxSimulator::step(double t_s) {
  // the encoder counts of the script's sample (the inverse of the bridge's calibration)
  const InstrumentReading r = script_.sample(t_s);
  const auto insertion = static_cast<long long>(std::llround(r.insertion_mm / cal_.mm_per_count)) +
                         static_cast<long long>(cal_.insertion_zero_counts);
  const auto rotation = static_cast<long long>(std::llround(r.rotation_rad / cal_.rad_per_count));
  // a line the pty took in part is finished first; while it is stuck, this sample is skipped
  if (!out_.empty()) {
    const ssize_t w = ::write(master_, out_.data(), out_.size());
    if (w > 0) out_.erase(0, static_cast<size_t>(w));
  }
  if (out_.empty()) {
    char line[96];
    const int n = std::snprintf(line, sizeof line, "E %lld %lld %d\n", insertion, rotation, r.buttons);
    const ssize_t w = n > 0 ? ::write(master_, line, static_cast<size_t>(n)) : -1;
    if (w > 0) {
      ++sent_;
      if (w < n) out_.assign(line + w, static_cast<size_t>(n - w));
    }
  }
  read_forces(t_s);
}

void BoxSimulator::read_forces(double t_s) {
  char buf[1024];
  for (;;) {
    const ssize_t n = ::read(master_, buf, sizeof buf);
    if (n <= 0) break;
    for (ssize_t i = 0; i < n; ++i) {
      if (buf[i] != '\n') {
        if (pending_.size() < 200) pending_.push_back(buf[i]);
        continue;
      }
      ForceLine f;
      if (parse_force_line(pending_, f)) {
        ++received_;
        last_ = f;
        last_line_t_s_ = t_s;
        if (static_cast<int64_t>(log_.size()) < max_log_) log_.push_back({t_s, f});
      } else if (!pending_.empty()) {
        ++malformed_;
      }
      pending_.clear();
    }
  }
}

bool BoxSimulator::watchdog_tripped(double t_s) const {
  return last_line_t_s_ < 0 || t_s - last_line_t_s_ > kBoxWatchdogS;
}

double BoxSimulator::applied_axial_n(double t_s) const {
  return watchdog_tripped(t_s) ? 0.0 : last_.axial_mn * 1e-3;
}

double BoxSimulator::applied_torque_nmm(double t_s) const {
  return watchdog_tripped(t_s) ? 0.0 : last_.torque_unm * 1e-3;
}

void BoxSimulator::write_csv(const std::string& path) const {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write the box's force log");
  out << "t_s,axial_mN,torque_uNm,seq\n";
  for (const BoxForceSample& s : log_)
    out << fmt::format("{:.6f},{},{},{}\n", s.t_s, s.line.axial_mn, s.line.torque_unm, s.line.seq);
  if (!out) throw std::runtime_error(path + ": write failed");
}

}  // namespace pcisim::clients
