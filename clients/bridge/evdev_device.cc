#include "clients/bridge/evdev_device.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <linux/input.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <numbers>
#include <chrono>
#include <stdexcept>
#include <tuple>

#include "realtime/clock.h"
#include "realtime/realtime_setup.h"

namespace pcisim::clients {
namespace {

struct Named {
  const char* name;
  int code;
};
constexpr Named kAxes[] = {{"ABS_X", ABS_X},
                           {"ABS_Y", ABS_Y},
                           {"ABS_Z", ABS_Z},
                           {"ABS_RX", ABS_RX},
                           {"ABS_RY", ABS_RY},
                           {"ABS_RZ", ABS_RZ},
                           {"ABS_THROTTLE", ABS_THROTTLE},
                           {"ABS_RUDDER", ABS_RUDDER},
                           {"ABS_WHEEL", ABS_WHEEL},
                           {"ABS_GAS", ABS_GAS},
                           {"ABS_BRAKE", ABS_BRAKE}};
constexpr Named kKeys[] = {{"BTN_0", BTN_0},
                           {"BTN_1", BTN_1},
                           {"BTN_2", BTN_2},
                           {"BTN_3", BTN_3},
                           {"BTN_TRIGGER", BTN_TRIGGER},
                           {"BTN_THUMB", BTN_THUMB},
                           {"BTN_THUMB2", BTN_THUMB2},
                           {"BTN_TOP", BTN_TOP},
                           {"BTN_TOP2", BTN_TOP2},
                           {"BTN_PINKIE", BTN_PINKIE},
                           {"BTN_BASE", BTN_BASE},
                           {"BTN_BASE2", BTN_BASE2},
                           {"BTN_SOUTH", BTN_SOUTH},
                           {"BTN_EAST", BTN_EAST},
                           {"BTN_NORTH", BTN_NORTH},
                           {"BTN_WEST", BTN_WEST}};

// a table's code for `name`, or `name` read as a number below `limit`; -1 otherwise
template <size_t N>
int lookup(const Named (&table)[N], std::string_view name, int limit) {
  for (const Named& n : table)
    if (name == n.name) return n.code;
  int code = -1;
  const auto [end, ec] = std::from_chars(name.data(), name.data() + name.size(), code);
  return ec == std::errc() && end == name.data() + name.size() && code >= 0 && code < limit ? code : -1;
}

constexpr size_t bytes_for(int bits) {
  return static_cast<size_t>(bits + 7) / 8;
}
bool bit(const unsigned char* bits, int n) {
  return (bits[n / 8] >> (n % 8)) & 1;
}

}  // namespace

int evdev_axis_code(std::string_view name) {
  return lookup(kAxes, name, ABS_CNT);
}
int evdev_key_code(std::string_view name) {
  return name == "none" ? -1 : lookup(kKeys, name, KEY_CNT);
}

void validate(const EvdevConfig& c) {
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("evdev: " + what);
  };
  require(c.insertion_axis >= 0 && c.insertion_axis < ABS_CNT,
          fmt::format("insertion axis {} is not an absolute axis", c.insertion_axis));
  require(c.rotation_axis >= 0 && c.rotation_axis < ABS_CNT,
          fmt::format("rotation axis {} is not an absolute axis", c.rotation_axis));
  require(c.insertion_axis != c.rotation_axis, "insertion and rotation need two different axes");
  require(
      std::isfinite(c.min_insertion_mm) && std::isfinite(c.max_insertion_mm) &&
          c.min_insertion_mm != c.max_insertion_mm,
      fmt::format("insertion range [{}, {}] mm must be finite and not empty", c.min_insertion_mm, c.max_insertion_mm));
  require(std::isfinite(c.wheel_range_deg) && c.wheel_range_deg != 0.0 && std::abs(c.wheel_range_deg) <= 3600.0,
          fmt::format("wheel_range_deg {} must be non-zero and within +-3600", c.wheel_range_deg));
  require(std::isfinite(c.full_scale_torque_nmm) && c.full_scale_torque_nmm > 0.0,
          fmt::format("full_scale_torque_nmm {} must be finite and > 0", c.full_scale_torque_nmm));
  require(std::isfinite(c.gain) && c.gain > 0.0 && c.gain <= 1.0, fmt::format("gain {} must be in (0, 1]", c.gain));
  for (int key : {c.fluoro_key, c.cine_key, c.contrast_key})
    require(key >= -1 && key < KEY_CNT, fmt::format("key {} is not a key code", key));
}

int16_t constant_level(double torque_nmm, double full_scale_torque_nmm) {
  const double x = torque_nmm / full_scale_torque_nmm * 0x7fff;
  if (!std::isfinite(x)) return 0;
  return static_cast<int16_t>(std::lround(std::clamp(x, -32767.0, 32767.0)));
}

int16_t spring_coefficient(double stiffness_nmm_per_rad, const EvdevConfig& c) {
  const double half_range_rad = 0.5 * std::abs(c.wheel_range_deg) * std::numbers::pi / 180.0;
  const double x = stiffness_nmm_per_rad * half_range_rad / c.full_scale_torque_nmm * 0x7fff;
  if (!std::isfinite(x)) return 0;
  return static_cast<int16_t>(std::lround(std::clamp(x, 0.0, 32767.0)));
}

EvdevDevice::EvdevDevice(const std::string& event_path, const EvdevConfig& config) : path_(event_path), cfg_(config) {
  validate(config);
  fd_ = ::open(event_path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0)
    throw std::runtime_error(fmt::format("{}: cannot open the event device: {}", event_path, std::strerror(errno)));
  auto fail = [&](const std::string& what) {
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error(fmt::format("{}: {}", event_path, what));
  };
  char name[256] = {};
  if (ioctl(fd_, EVIOCGNAME(sizeof name - 1), name) < 0) fail("not an event device (EVIOCGNAME refused)");
  name_ = name;
  unsigned char types[bytes_for(EV_CNT)] = {}, abs[bytes_for(ABS_CNT)] = {}, ff[bytes_for(FF_CNT)] = {};
  ioctl(fd_, EVIOCGBIT(0, sizeof types), types);
  ioctl(fd_, EVIOCGBIT(EV_ABS, sizeof abs), abs);
  ioctl(fd_, EVIOCGBIT(EV_FF, sizeof ff), ff);
  for (auto [axis, code, role] : {std::tuple{&insertion_, cfg_.insertion_axis, "insertion"},
                                  std::tuple{&rotation_, cfg_.rotation_axis, "rotation"}}) {
    input_absinfo info{};
    if (!bit(types, EV_ABS) || !bit(abs, code) || ioctl(fd_, EVIOCGABS(code), &info) < 0)
      fail(fmt::format("'{}' has no absolute axis {} for the {}", name_, code, role));
    if (info.maximum <= info.minimum)
      fail(fmt::format("'{}': axis {} for the {} has an empty range [{}, {}]", name_, code, role, info.minimum,
                       info.maximum));
    *axis = {code, info.minimum, info.maximum, std::clamp(info.value, info.minimum, info.maximum)};
  }
  int effects = 0;
  if (!bit(types, EV_FF) || !bit(ff, FF_CONSTANT))
    fail(fmt::format("'{}' declares no FF_CONSTANT force feedback: it cannot render the torque", name_));
  if (ioctl(fd_, EVIOCGEFFECTS, &effects) < 0 || effects < 1)
    fail(fmt::format("'{}' has room for no force-feedback effect", name_));
  has_gain_ = bit(ff, FF_GAIN);
  has_spring_ = bit(ff, FF_SPRING) && effects >= 2;
  has_autocenter_ = bit(ff, FF_AUTOCENTER);
  // the device's settings: our gain, its own centring spring off (it would fight the wire)
  auto set = [&](int code, double value) {
    input_event ev{};
    ev.type = EV_FF;
    ev.code = static_cast<uint16_t>(code);
    ev.value = static_cast<int32_t>(std::lround(value * 0xffff));
    if (::write(fd_, &ev, sizeof ev) != static_cast<ssize_t>(sizeof ev))
      fail(fmt::format("'{}' refused force-feedback setting {}: {}", name_, code, std::strerror(errno)));
  };
  if (has_gain_) set(FF_GAIN, cfg_.gain);
  if (has_autocenter_) set(FF_AUTOCENTER, 0.0);
  resync();
  for (auto& slot : positions_) slot = {-1, 0};
  wanted_ = applied_ = pack(0, 0, 0, 0);
  writer_ = std::thread([this] { write_loop(); });
}

EvdevDevice::~EvdevDevice() {
  stop_ = true;
  wanted_.fetch_xor(uint64_t{1} << 63);  // a change, to wake the writer
  wanted_.notify_all();
  if (writer_.joinable()) writer_.join();
  stop_both();
  for (const int16_t id : {effect_id_, spring_id_})
    if (id >= 0) ioctl(fd_, EVIOCRMFF, static_cast<long>(id));
  ::close(fd_);
}

bool EvdevDevice::query_state(int32_t& insertion, int32_t& rotation, int32_t& buttons) const {
  input_absinfo info{};
  if (ioctl(fd_, EVIOCGABS(insertion_.code), &info) < 0) return false;
  insertion = info.value;
  if (ioctl(fd_, EVIOCGABS(rotation_.code), &info) < 0) return false;
  rotation = info.value;
  unsigned char keys[bytes_for(KEY_CNT)] = {};
  if (ioctl(fd_, EVIOCGKEY(sizeof keys), keys) < 0) return false;
  buttons = 0;
  const int map[3][2] = {{cfg_.fluoro_key, 1}, {cfg_.cine_key, 2}, {cfg_.contrast_key, 4}};
  for (const auto& m : map)
    if (m[0] >= 0 && bit(keys, m[0])) buttons |= m[1];
  return true;
}

void EvdevDevice::resync() {
  int32_t insertion = 0, rotation = 0, buttons = 0;
  if (!query_state(insertion, rotation, buttons)) return;
  insertion_.value = std::clamp(insertion, insertion_.min, insertion_.max);
  rotation_.value = std::clamp(rotation, rotation_.min, rotation_.max);
  buttons_ = buttons;
}

double EvdevDevice::insertion_mm() const {
  const double u = static_cast<double>(insertion_.value - insertion_.min) / (insertion_.max - insertion_.min);
  return cfg_.min_insertion_mm + u * (cfg_.max_insertion_mm - cfg_.min_insertion_mm);
}

double EvdevDevice::rotation_rad() const {
  const double mid = 0.5 * (static_cast<double>(rotation_.min) + rotation_.max);
  const double u = (rotation_.value - mid) / (static_cast<double>(rotation_.max) - rotation_.min);
  return u * cfg_.wheel_range_deg * std::numbers::pi / 180.0;
}

bool EvdevDevice::read(double t_s, InstrumentReading& out) {
  input_event events[64];
  bool moved = false;
  // the writer's answer to a resync asked for below (the kernel's state queries wait for its lock,
  // which an upload holds)
  if (const int64_t v = resynced_version_.load(std::memory_order_acquire); v != resync_seen_) {
    resync_seen_ = v;
    insertion_.value = std::clamp(resynced_insertion_.load(), insertion_.min, insertion_.max);
    rotation_.value = std::clamp(resynced_rotation_.load(), rotation_.min, rotation_.max);
    buttons_ = resynced_buttons_.load();
    moved = true;
  }
  while (!unplugged_) {
    const ssize_t n = ::read(fd_, events, sizeof events);
    if (n < 0) {
      if (errno == EAGAIN || errno == EINTR) break;
      unplugged_ = true;  // ENODEV: the device went away
      break;
    }
    if (n == 0) break;
    for (ssize_t i = 0; i < n / static_cast<ssize_t>(sizeof(input_event)); ++i) {
      const input_event& e = events[i];
      if (e.type == EV_SYN && e.code == SYN_DROPPED) {
        dropped_ = true;  // the kernel's buffer overflowed: ask for the state at the next report
      } else if (e.type == EV_SYN && e.code == SYN_REPORT && dropped_) {
        dropped_ = false;
        resync_wanted_ = true;
        hand_over(last_wanted_);
      } else if (dropped_) {
        continue;
      } else if (e.type == EV_ABS) {
        for (Axis* a : {&insertion_, &rotation_})
          if (e.code == a->code) a->value = std::clamp(e.value, a->min, a->max), moved = true;
      } else if (e.type == EV_KEY) {
        const int map[3][2] = {{cfg_.fluoro_key, 1}, {cfg_.cine_key, 2}, {cfg_.contrast_key, 4}};
        for (const auto& m : map)
          if (m[0] == e.code) buttons_ = e.value ? (buttons_ | m[1]) : (buttons_ & ~m[1]);
      }
    }
  }
  if (unplugged_ || stuck()) return false;
  const double x = insertion_mm(), r = rotation_rad();
  if (moved) {
    const double dt = last_event_t_s_ >= 0 ? t_s - last_event_t_s_ : 0.0;
    if (dt > 1e-4) {
      insertion_rate_mm_s_ = (x - last_insertion_mm_) / dt;
      rotation_rate_rad_s_ = (r - last_rotation_rad_) / dt;
    }
    last_event_t_s_ = t_s;
    last_insertion_mm_ = x;
    last_rotation_rad_ = r;
  } else if (last_event_t_s_ < 0 || t_s - last_event_t_s_ > 0.05) {
    // still: a device reports only changes; the next motion's rate counts from now
    insertion_rate_mm_s_ = rotation_rate_rad_s_ = 0.0;
    last_event_t_s_ = t_s;
    last_insertion_mm_ = x;
    last_rotation_rad_ = r;
  }
  out.insertion_mm = x;
  out.rotation_rad = r;
  out.insertion_rate_mm_s = insertion_rate_mm_s_;
  out.rotation_rate_rad_s = rotation_rate_rad_s_;
  out.buttons = buttons_;
  return true;
}

// an effect to the kernel (EVIOCSFF): its id set on success; a refusal counted, ENODEV unplugged
bool EvdevDevice::send_effect(ff_effect& e) {
  if (ioctl(fd_, EVIOCSFF, &e) == 0) return true;
  if (errno == ENODEV) unplugged_ = true;
  ++failed_writes_;
  return false;
}

// one constant effect, infinite, along the wheel (direction 0x4000); a new level replaces the
// old one under the same id (the kernel updates a playing effect in place)
bool EvdevDevice::upload(int16_t level) {
  ff_effect e{};
  e.type = FF_CONSTANT;
  e.id = effect_id_;
  e.direction = 0x4000;
  e.u.constant.level = level;
  if (!send_effect(e)) return false;
  effect_id_ = e.id;
  level_ = level;
  ++uploads_;
  return true;
}

// a spring on the wheel's axis (condition[0]: the X axis's slot), the same coefficient either
// side of its centre, no dead band, not saturated
bool EvdevDevice::upload_spring(int16_t coefficient, int16_t centre) {
  ff_effect e{};
  e.type = FF_SPRING;
  e.id = spring_id_;
  e.direction = 0x4000;
  e.u.condition[0].right_coeff = e.u.condition[0].left_coeff = coefficient;
  e.u.condition[0].right_saturation = e.u.condition[0].left_saturation = 0xffff;
  e.u.condition[0].center = centre;
  if (!send_effect(e)) return false;
  spring_id_ = e.id;
  spring_coefficient_ = coefficient;
  spring_centre_ = centre;
  ++spring_uploads_;
  return true;
}

bool EvdevDevice::play(int16_t id, bool on, std::atomic<bool>& playing) {
  input_event ev{};
  ev.type = EV_FF;
  ev.code = static_cast<uint16_t>(id);
  ev.value = on ? 1 : 0;
  if (::write(fd_, &ev, sizeof ev) != static_cast<ssize_t>(sizeof ev)) {
    if (errno == ENODEV) unplugged_ = true;
    ++failed_writes_;
    return false;
  }
  playing = on;
  return true;
}

void EvdevDevice::stop_both() {
  if (playing_) play(effect_id_, false, playing_);
  if (spring_playing_) play(spring_id_, false, spring_playing_);
  level_ = 0;
  spring_coefficient_ = 0;
}

int16_t EvdevDevice::centre_of(int32_t axis_value) const {
  const double mid = 0.5 * (static_cast<double>(rotation_.min) + rotation_.max);
  const double u = (axis_value - mid) / (0.5 * (static_cast<double>(rotation_.max) - rotation_.min));
  return static_cast<int16_t>(std::lround(std::clamp(u, -1.0, 1.0) * 32767.0));
}

uint64_t EvdevDevice::pack(int16_t level, int16_t coefficient, int16_t centre, uint16_t version) {
  return uint64_t{static_cast<uint16_t>(level)} | uint64_t{static_cast<uint16_t>(coefficient)} << 16 |
         uint64_t{static_cast<uint16_t>(centre)} << 32 | uint64_t{version} << 48;
}

EvdevDevice::Wanted EvdevDevice::unpack(uint64_t w) {
  return {static_cast<int16_t>(w & 0xffff), static_cast<int16_t>((w >> 16) & 0xffff),
          static_cast<int16_t>((w >> 32) & 0xffff)};
}

void EvdevDevice::hand_over(const Wanted& w) {
  last_wanted_ = w;
  wanted_.store(pack(w.level, w.coefficient, w.centre, ++version_), std::memory_order_release);
  wanted_.notify_one();
}

bool EvdevDevice::stuck() const {
  const int64_t since = busy_since_ns_.load(std::memory_order_relaxed);
  return since > 0 && realtime::monotonic_ns() - since > kStuckNs;
}

// the 1 kHz loop's side: the set-point as levels, handed over. A flipped wheel (negative range)
// flips the torque too, so that it still resists the trainee's turn in the device's own terms
bool EvdevDevice::render(const ForceSetpoint& force, int64_t seq) {
  positions_[static_cast<size_t>(seq) % kPositionSlots] = {seq, rotation_.value};
  if (unplugged_) return false;
  const double sign = cfg_.wheel_range_deg < 0.0 ? -1.0 : 1.0;
  Wanted w;
  w.level = constant_level(sign * force.torque_nmm, cfg_.full_scale_torque_nmm);
  if (has_spring_) {
    w.coefficient = spring_coefficient(force.torsional_stiffness_nmm_per_rad, cfg_);
    // where the wheel stood at the sample the torque answers (the server evaluated the torque
    // there): the spring adds Kt times the turn since; now when that sample is not kept
    const auto& at = positions_[static_cast<size_t>(std::max<int64_t>(force.sample_seq, 0)) % kPositionSlots];
    w.centre = centre_of(force.sample_seq >= 0 && at.first == force.sample_seq ? at.second : rotation_.value);
  }
  // a zero is sticky: the writer stops both effects before it applies anything newer
  if (w.level == 0 && w.coefficient == 0) zero_pending_ = true;
  const bool same =
      w.level == last_wanted_.level && w.coefficient == last_wanted_.coefficient && w.centre == last_wanted_.centre;
  if (!same || retry_.exchange(false)) hand_over(w);
  return !stuck();
}

bool EvdevDevice::flush(double timeout_s) {
  const int64_t until = realtime::monotonic_ns() + static_cast<int64_t>(timeout_s * 1e9);
  while (applied_.load() != wanted_.load() && !unplugged_) {
    if (realtime::monotonic_ns() > until) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return true;
}

// the writer: the newest set-point, applied; those in between are skipped, a zero never
void EvdevDevice::write_loop() {
  realtime::try_sched_fifo(kWriterFifoPriority);  // where permitted: a fault's zero must not queue
  uint64_t applied = applied_.load();
  for (;;) {
    wanted_.wait(applied, std::memory_order_acquire);
    if (stop_) return;
    const uint64_t w = wanted_.load(std::memory_order_acquire);
    busy_since_ns_ = realtime::monotonic_ns();
    if (resync_wanted_.exchange(false)) {
      int32_t insertion = 0, rotation = 0, buttons = 0;
      if (query_state(insertion, rotation, buttons)) {
        resynced_insertion_ = insertion;
        resynced_rotation_ = rotation;
        resynced_buttons_ = buttons;
        resynced_version_.fetch_add(1, std::memory_order_release);
      }
    }
    apply(unpack(w));
    busy_since_ns_ = 0;
    applied = w;
    applied_.store(w);
  }
}

void EvdevDevice::apply(const Wanted& w) {
  if (unplugged_) return;
  if (zero_pending_.exchange(false)) stop_both();
  apply_constant(w.level);
  // a zero that came meanwhile goes first
  if (zero_pending_.exchange(false)) {
    stop_both();
    return;
  }
  if (has_spring_) apply_spring(w.coefficient, w.centre);
}

// zero stops the effect: nothing pushes the hand; so does an upload that failed (the old level
// would play on), and the loop hands the same set-point over again
void EvdevDevice::apply_constant(int16_t level) {
  if (level != 0) {
    const bool current = effect_id_ >= 0 && level == level_;
    if ((current || upload(level)) && (playing_ || play(effect_id_, true, playing_))) return;
    retry_ = true;
  }
  if (playing_) play(effect_id_, false, playing_);
  level_ = 0;
}

// the spring: re-centred once its centre moved a few counts, so that it adds the turn since the
// sample the torque answers and nothing the constant effect already gives
void EvdevDevice::apply_spring(int16_t coefficient, int16_t centre) {
  constexpr int kCentreToleranceCounts = 4;  // of 65535 over the axis: 0.05 deg of a 900 deg wheel
  if (coefficient != 0) {
    const bool current = spring_id_ >= 0 && coefficient == spring_coefficient_ &&
                         std::abs(centre - spring_centre_) <= kCentreToleranceCounts;
    if ((current || upload_spring(coefficient, centre)) && (spring_playing_ || play(spring_id_, true, spring_playing_)))
      return;
    retry_ = true;
  }
  if (spring_playing_) play(spring_id_, false, spring_playing_);
  spring_coefficient_ = 0;
}

std::string EvdevDevice::describe() const {
  return fmt::format(
      "force-feedback device '{}' on {} (insertion axis {}, rotation axis {} over {} deg, full scale "
      "{} N mm{}{})",
      name_, path_, insertion_.code, rotation_.code, cfg_.wheel_range_deg, cfg_.full_scale_torque_nmm,
      has_gain_ ? fmt::format(", gain {}", cfg_.gain) : std::string(", no gain control"),
      has_spring_ ? ", the stiffness as a spring" : ", no spring: the stiffness is not rendered");
}

}  // namespace pcisim::clients
