#pragma once
// A Linux force-feedback input device (a wheel, a joystick) as the instrument: the kernel's evdev
// interface, no vendor SDK (docs/serial-protocol.md, "A force-feedback device"). Positions come
// from two absolute axes (insertion from a pedal or a stick's axis, rotation from the wheel), the
// pedals' buttons from keys; the server's torque is rendered as one FF_CONSTANT effect, updated
// in place when its level changes, and its rise with twist (the local model's stiffness) as an
// FF_SPRING centred where the wheel stood at the sample the torque answers, where the device has
// one; both stopped whenever the set-point is zero (every fault sends zero, force_gate.h) and
// erased on exit. A thread of its own talks to the device, so that an upload that waits for it
// never holds the 1 kHz loop. A wheel renders no axial force: only the torque. A positive level
// (direction 0x4000) is taken to push the wheel towards lower axis values; a device that pushes
// the other way needs the profile's torque_scale negative.
#include <linux/input.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>
#include <utility>
#include <string>
#include <string_view>

#include "clients/bridge/instrument_device.h"

namespace pcisim::clients {

struct EvdevConfig {
  int insertion_axis = 0x01;  // ABS_Y: its whole travel spans [min, max]_insertion_mm
  int rotation_axis = 0x00;   // ABS_X: its whole travel spans wheel_range_deg, its middle is 0
  double min_insertion_mm = 0.0, max_insertion_mm = 200.0;  // max < min flips the axis
  double wheel_range_deg = 900.0;                           // negative flips the wheel
  // the torque at the effect's full level (0x7fff), N mm: the server's peak (0.02 N m) by default,
  // so the largest torque the server sends is the device's strongest
  double full_scale_torque_nmm = 20.0;
  double gain = 1.0;                                               // FF_GAIN, (0, 1], where the device has it
  int fluoro_key = 0x100, cine_key = 0x101, contrast_key = 0x102;  // BTN_0 ... BTN_2; -1: none
};

// throws std::invalid_argument ("evdev: ...") naming the bad value
void validate(const EvdevConfig& config);

// "ABS_X", "ABS_GAS", ... or a number; -1 when the name is unknown
int evdev_axis_code(std::string_view name);
// "BTN_0", "BTN_TRIGGER", ... or a number; -1 when unknown ("none" is -1 too)
int evdev_key_code(std::string_view name);

// the effect's level for a torque (N mm): round(torque / full scale * 0x7fff), clamped
int16_t constant_level(double torque_nmm, double full_scale_torque_nmm);
// the spring's coefficient for a torsional stiffness (N mm / rad): the level of the torque it
// gives half the wheel's range away from its centre, clamped to [0, 0x7fff]
int16_t spring_coefficient(double stiffness_nmm_per_rad, const EvdevConfig& config);

class EvdevDevice : public InstrumentDevice {
 public:
  // opens the event node read-write and non-blocking and checks what it declares: both axes, and
  // FF_CONSTANT with room for one effect; sets the gain (FF_GAIN) and turns the device's own
  // centring spring off (FF_AUTOCENTER) where it has them. Throws std::runtime_error naming the
  // node and what it lacks. Starts the writer thread (below)
  EvdevDevice(const std::string& event_path, const EvdevConfig& config);
  ~EvdevDevice() override;  // stops the writer, then stops and erases the effects
  EvdevDevice(const EvdevDevice&) = delete;
  EvdevDevice& operator=(const EvdevDevice&) = delete;

  // drains the node's events; false once it is gone (unplugged: ENODEV)
  bool read(double t_s, InstrumentReading& out) override;
  // hands the set-point to the writer thread and returns (one atomic store: no lock, no
  // allocation): an upload (EVIOCSFF) may wait for the device — hid-pidff waits for its reports to
  // go out, a uinput device for its maker's answer, and the kernel holds the device's lock all the
  // while — which the 1 kHz loop must not. The writer applies the newest set-point: the torque as
  // the constant effect (uploaded when its level changes, played from the first non-zero level,
  // stopped at zero or when an upload fails), the torsional stiffness as the spring centred where
  // the wheel stood at the sample the torque answers (re-uploaded when that moved a few counts or
  // the coefficient changed). A zero (every fault sends one) is never skipped: it stops both
  // effects before anything newer is applied. False once the device is unplugged, or while the
  // writer has been stuck on one apply for over kStuckNs (the device is then in fault)
  bool render(const ForceSetpoint& force, int64_t seq) override;
  std::string describe() const override;
  // waits until the writer has applied the newest set-point, or the device is gone (at most
  // timeout_s); false on timeout
  bool flush(double timeout_s = 1.0);
  // the writer busy on one apply this long: the device is in fault
  static constexpr int64_t kStuckNs = 30'000'000;

  int16_t level() const { return level_.load(); }  // as applied
  bool playing() const { return playing_.load(); }
  int64_t uploads() const { return uploads_.load(); }
  bool has_spring() const { return has_spring_; }
  bool spring_playing() const { return spring_playing_.load(); }
  int64_t spring_uploads() const { return spring_uploads_.load(); }
  int64_t failed_writes() const { return failed_writes_.load(); }
  bool unplugged() const { return unplugged_.load(); }
  bool has_gain() const { return has_gain_; }

 private:
  struct Axis {
    int code = 0;
    int32_t min = 0, max = 0, value = 0;
  };
  // what the writer should make the device do, packed in one word: level, coefficient and
  // centre (int16 each) and a 16-bit version that changes with every hand-over
  static uint64_t pack(int16_t level, int16_t coefficient, int16_t centre, uint16_t version);
  struct Wanted {
    int16_t level = 0, coefficient = 0, centre = 0;
  };
  static Wanted unpack(uint64_t w);
  void hand_over(const Wanted& w);  // the loop's side: a new version of w, and a wake-up
  // the axes' and keys' state asked of the kernel: into the members at start, then by the writer
  // (after SYN_DROPPED) into the resynced_ atomics, which the loop takes at its next read
  bool query_state(int32_t& insertion, int32_t& rotation, int32_t& buttons) const;
  void resync();
  // the writer's SCHED_FIFO priority where permitted: below the bridge's loop (60)
  static constexpr int kWriterFifoPriority = 59;
  void write_loop();
  void apply(const Wanted& w);
  bool stuck() const;
  bool send_effect(ff_effect& e);
  bool upload(int16_t level);
  bool upload_spring(int16_t coefficient, int16_t centre);
  bool play(int16_t id, bool on, std::atomic<bool>& playing);
  void stop_both();
  void apply_constant(int16_t level);
  void apply_spring(int16_t coefficient, int16_t centre);
  double insertion_mm() const;
  double rotation_rad() const;
  int16_t centre_of(int32_t axis_value) const;  // a wheel position as a spring's centre, +-0x7fff

  std::string path_, name_;
  int fd_ = -1;
  EvdevConfig cfg_;
  Axis insertion_, rotation_;
  int32_t buttons_ = 0;
  bool has_gain_ = false, has_autocenter_ = false, has_spring_ = false, dropped_ = false;
  // rates: from the positions at the last read that brought an event
  double last_event_t_s_ = -1, last_insertion_mm_ = 0, last_rotation_rad_ = 0;
  double insertion_rate_mm_s_ = 0, rotation_rate_rad_s_ = 0;
  // the wheel's position at each recent tick (seq % size, tagged with the seq): a spring's centre
  static constexpr int kPositionSlots = 256;
  std::array<std::pair<int64_t, int32_t>, kPositionSlots> positions_{};
  // the 1 kHz loop and the writer: the newest set-point, what the writer applied, a zero not yet
  // applied, a resync asked for (after SYN_DROPPED) and its answer, since when the writer is busy
  std::atomic<uint64_t> wanted_{0}, applied_{0};
  uint16_t version_ = 0;  // the loop's
  Wanted last_wanted_;    // the loop's
  std::atomic<bool> zero_pending_{false}, retry_{false}, resync_wanted_{false}, stop_{false};
  std::atomic<int32_t> resynced_insertion_{0}, resynced_rotation_{0}, resynced_buttons_{0};
  std::atomic<int64_t> resynced_version_{0}, busy_since_ns_{0};
  int64_t resync_seen_ = 0;  // the loop's
  std::thread writer_;
  // the writer's own (the accessors read them)
  int16_t effect_id_ = -1, spring_id_ = -1, spring_coefficient_ = 0, spring_centre_ = 0;
  std::atomic<int16_t> level_{0};
  std::atomic<bool> playing_{false}, spring_playing_{false}, unplugged_{false};
  std::atomic<int64_t> uploads_{0}, spring_uploads_{0}, failed_writes_{0};
};

}  // namespace pcisim::clients
