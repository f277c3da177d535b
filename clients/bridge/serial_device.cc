#include "clients/bridge/serial_device.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace pcisim::clients {
namespace {

speed_t baud_constant(int baud) {
  switch (baud) {
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 921600:
      return B921600;
    default:
      throw std::runtime_error(fmt::format("baud {} is not supported (9600 ... 921600)", baud));
  }
}

// reads one signed decimal field starting at p, skipping spaces; false when there is none
bool field(const char*& p, const char* end, int64_t& out) {
  while (p < end && *p == ' ') ++p;
  const auto [next, ec] = std::from_chars(p, end, out);
  if (ec != std::errc() || next == p) return false;
  p = next;
  return true;
}

// what an encoder can count (written out, not std::abs: there is no +INT64_MIN)
bool counts_in_range(int64_t c) {
  constexpr int64_t kMaxCounts = int64_t{1} << 40;
  return c >= -kMaxCounts && c <= kMaxCounts;
}

}  // namespace

// "E <insertion counts> <rotation counts> <buttons>" (docs/serial-protocol.md)
bool parse_encoder_line(const std::string& line, EncoderLine& out) {
  const char* p = line.data();
  const char* end = p + line.size();
  if (end > p && end[-1] == '\r') --end;
  if (end - p < 2 || p[0] != 'E' || p[1] != ' ') return false;
  p += 1;
  int64_t buttons = 0;
  if (!field(p, end, out.insertion_counts) || !field(p, end, out.rotation_counts) || !field(p, end, buttons))
    return false;
  while (p < end && *p == ' ') ++p;
  if (p != end || buttons < 0 || buttons > 0xffff) return false;
  // counts beyond 2^40 come from no encoder (and would overflow the zero offset): malformed
  if (!counts_in_range(out.insertion_counts) || !counts_in_range(out.rotation_counts)) return false;
  out.buttons = static_cast<int32_t>(buttons);
  return true;
}

void validate(const SerialCalibration& c) {
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("serial calibration: " + what);
  };
  require(std::isfinite(c.mm_per_count) && c.mm_per_count != 0.0, "mm_per_count must be finite and non-zero");
  require(std::isfinite(c.rad_per_count) && c.rad_per_count != 0.0, "rad_per_count must be finite and non-zero");
  require(counts_in_range(c.insertion_zero_counts), "insertion_zero_counts must be within +-2^40");
  require(std::isfinite(c.min_insertion_mm) && std::isfinite(c.max_insertion_mm) &&
              c.min_insertion_mm <= c.max_insertion_mm,
          fmt::format("insertion range [{}, {}] mm must be finite with min <= max", c.min_insertion_mm,
                      c.max_insertion_mm));
  require(std::isfinite(c.silent_timeout_s) && c.silent_timeout_s > 0.0, "silent_timeout_s must be finite and > 0");
}

SerialDevice::SerialDevice(const std::string& port, int baud, const SerialCalibration& calibration)
    : port_(port), cal_(calibration) {
  validate(calibration);
  const speed_t speed = baud_constant(baud);
  fd_ = ::open(port.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (fd_ < 0) throw std::runtime_error(fmt::format("{}: cannot open the serial port: {}", port, std::strerror(errno)));
  termios tio{};
  if (tcgetattr(fd_, &tio) == 0) {
    cfmakeraw(&tio);
    cfsetispeed(&tio, speed);
    cfsetospeed(&tio, speed);
    tcsetattr(fd_, TCSANOW, &tio);
  }
  pending_.reserve(4096);
}

SerialDevice::~SerialDevice() {
  if (fd_ >= 0) ::close(fd_);
}

void SerialDevice::take(const EncoderLine& e, double t_s) {
  const double counts = static_cast<double>(e.insertion_counts) - static_cast<double>(cal_.insertion_zero_counts);
  const double insertion_mm = std::clamp(counts * cal_.mm_per_count, cal_.min_insertion_mm, cal_.max_insertion_mm);
  const double rotation_rad = e.rotation_counts * cal_.rad_per_count;
  // rates from successive samples; the first sample has none
  const double dt = last_sample_t_s_ >= 0 ? t_s - last_sample_t_s_ : 0.0;
  reading_.insertion_rate_mm_s = dt > 1e-4 ? (insertion_mm - last_insertion_mm_) / dt : reading_.insertion_rate_mm_s;
  reading_.rotation_rate_rad_s = dt > 1e-4 ? (rotation_rad - last_rotation_rad_) / dt : reading_.rotation_rate_rad_s;
  reading_.insertion_mm = last_insertion_mm_ = insertion_mm;
  reading_.rotation_rad = last_rotation_rad_ = rotation_rad;
  reading_.buttons = e.buttons;
  last_sample_t_s_ = last_valid_t_s_ = t_s;
}

bool SerialDevice::read(double t_s, InstrumentReading& out) {
  char buf[1024];
  while (!unplugged_) {
    const ssize_t n = ::read(fd_, buf, sizeof buf);
    if (n > 0) {
      for (ssize_t i = 0; i < n; ++i) {
        if (buf[i] != '\n') {
          if (pending_.size() < kMaxLine)
            pending_.push_back(buf[i]);
          else
            overlong_ = true;
          continue;
        }
        EncoderLine e;
        if (overlong_) {
          ++malformed_;  // a cut line might still parse: never trust it
          overlong_ = false;
        } else if (pending_.empty() || pending_[0] == '#') {
          // blank lines and comments are not samples
        } else if (parse_encoder_line(pending_, e)) {
          ++lines_;
          take(e, t_s);
        } else {
          ++malformed_;
        }
        pending_.clear();
      }
    } else if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
      unplugged_ = true;  // hang-up or a read error: the box is gone
    } else {
      break;
    }
  }
  if (unplugged_ || last_valid_t_s_ < 0 || t_s - last_valid_t_s_ > cal_.silent_timeout_s) return false;
  out = reading_;
  return true;
}

bool SerialDevice::render(const ForceSetpoint& force, int64_t seq) {
  if (unplugged_) return false;
  auto flush = [&] {
    while (out_begin_ < out_end_) {
      const ssize_t n = ::write(fd_, out_ + out_begin_, out_end_ - out_begin_);
      if (n > 0) {
        out_begin_ += static_cast<size_t>(n);
      } else if (n < 0 && errno == EINTR) {
        continue;
      } else {
        if (n < 0 && errno != EAGAIN) unplugged_ = true;  // EIO after a hang-up: the box is gone
        return false;
      }
    }
    return true;
  };
  // the tail of a line the port took in part goes first; while it is stuck, this line is dropped
  if (!flush()) {
    ++force_lines_dropped_;
    return false;
  }
  // a line slower than a line a tick (a low baud) must not queue force in the kernel, where a
  // fault's zero would wait behind it: while more than a line waits to go out, a force line is
  // dropped, and a zero line first discards what waits (a newline ends any line cut short)
  const bool zero = force.axial_n == 0.0 && force.torque_nmm == 0.0;
  int queued = 0;
  size_t lead = 0;
  if (::ioctl(fd_, TIOCOUTQ, &queued) == 0 && queued > static_cast<int>(kForceLineMaxBytes)) {
    if (!zero) {
      ++force_lines_dropped_;
      return false;
    }
    ::tcflush(fd_, TCOFLUSH);
    out_[0] = '\n';
    lead = 1;
  }
  out_begin_ = 0;
  out_end_ = lead + format_force_line(force, seq, out_ + lead);
  flush();
  if (out_begin_ == 0) {  // nothing of it went out
    out_end_ = 0;
    ++force_lines_dropped_;
    return false;
  }
  ++force_lines_;  // whole, or its tail goes first next tick
  return true;
}

std::string SerialDevice::describe() const {
  return fmt::format("serial encoder on {} ({} mm/count, {} rad/count)", port_, cal_.mm_per_count, cal_.rad_per_count);
}

}  // namespace pcisim::clients
