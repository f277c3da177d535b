#include "tests/clients/bridge/uinput_wheel.h"

#include <dirent.h>
#include <fcntl.h>
#include <linux/uinput.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "realtime/clock.h"

namespace pcisim::clients::testing {
namespace {

void must(int rc, const char* what) {
  if (rc < 0) throw std::runtime_error(std::string("uinput: ") + what + ": " + std::strerror(errno));
}

void emit(int fd, uint16_t type, uint16_t code, int32_t value) {
  input_event ev{};
  ev.type = type;
  ev.code = code;
  ev.value = value;
  must(static_cast<int>(::write(fd, &ev, sizeof ev)) == static_cast<int>(sizeof ev) ? 0 : -1, "write an event");
}

}  // namespace

std::string UinputWheel::unavailable() {
  const int fd = ::open("/dev/uinput", O_WRONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd >= 0) {
    ::close(fd);
    return "";
  }
  return std::string("/dev/uinput cannot be opened (") + std::strerror(errno) +
         "): this kernel or container offers no virtual input devices (CONFIG_INPUT_UINPUT); scripts/uinput-vm runs "
         "these tests in a virtual machine that has them";
}

UinputWheel::UinputWheel(const std::string& name) try {
  fd_ = ::open("/dev/uinput", O_RDWR | O_NONBLOCK | O_CLOEXEC);
  must(fd_, "open /dev/uinput");
  for (int ev : {EV_KEY, EV_ABS, EV_FF}) must(ioctl(fd_, UI_SET_EVBIT, ev), "UI_SET_EVBIT");
  for (int key : {BTN_0, BTN_1, BTN_2}) must(ioctl(fd_, UI_SET_KEYBIT, key), "UI_SET_KEYBIT");
  for (int abs : {ABS_X, ABS_Y}) must(ioctl(fd_, UI_SET_ABSBIT, abs), "UI_SET_ABSBIT");
  for (int ff : {FF_CONSTANT, FF_SPRING, FF_GAIN, FF_AUTOCENTER}) must(ioctl(fd_, UI_SET_FFBIT, ff), "UI_SET_FFBIT");
  uinput_setup setup{};
  setup.id.bustype = BUS_VIRTUAL;
  setup.id.vendor = 0x1209;  // pid.codes' test vendor
  setup.id.product = 0x0001;
  std::snprintf(setup.name, sizeof setup.name, "%s", name.c_str());
  setup.ff_effects_max = 4;
  must(ioctl(fd_, UI_DEV_SETUP, &setup), "UI_DEV_SETUP");
  const std::pair<int, input_absinfo> axes[] = {{ABS_X, {0, -32768, 32767, 0, 0, 0}}, {ABS_Y, {0, 0, 1023, 0, 0, 0}}};
  for (const auto& [code, info] : axes) {
    uinput_abs_setup abs{};
    abs.code = static_cast<uint16_t>(code);
    abs.absinfo = info;
    must(ioctl(fd_, UI_ABS_SETUP, &abs), "UI_ABS_SETUP");
  }
  must(ioctl(fd_, UI_DEV_CREATE), "UI_DEV_CREATE");
  // its event node: /sys/devices/virtual/input/<sysname>/eventN
  char sysname[64] = {};
  must(ioctl(fd_, UI_GET_SYSNAME(sizeof sysname), sysname), "UI_GET_SYSNAME");
  const std::string dir = std::string("/sys/devices/virtual/input/") + sysname;
  std::string event;
  for (int attempt = 0; attempt < 200 && event.empty(); ++attempt) {
    if (DIR* d = opendir(dir.c_str())) {
      while (dirent* e = readdir(d))
        if (std::strncmp(e->d_name, "event", 5) == 0) event = e->d_name;
      closedir(d);
    }
    if (event.empty()) usleep(5000);
  }
  if (event.empty()) throw std::runtime_error("uinput: " + dir + " has no event node (is evdev loaded?)");
  event_path_ = "/dev/input/" + event;
  if (::access(event_path_.c_str(), R_OK | W_OK) != 0) {
    // no devtmpfs here: make the node from the device number sysfs gives
    unsigned major_no = 0, minor_no = 0;
    std::ifstream dev(dir + "/" + event + "/dev");
    char colon = 0;
    if (!(dev >> major_no >> colon >> minor_no)) throw std::runtime_error("uinput: no device number for " + event);
    made_node_ = "/tmp/pcisim-uinput-" + std::to_string(getpid()) + "-" + event;
    must(mknod(made_node_.c_str(), S_IFCHR | 0600, makedev(major_no, minor_no)), "mknod the event node");
    event_path_ = made_node_;
  }
  thread_ = std::thread([this] { serve(); });
} catch (...) {
  // a half-made device goes with its descriptor
  if (fd_ >= 0) {
    ioctl(fd_, UI_DEV_DESTROY);
    ::close(fd_);
  }
  throw;
}

UinputWheel::~UinputWheel() {
  unplug();
  if (!made_node_.empty()) ::unlink(made_node_.c_str());
}

void UinputWheel::unplug() {
  if (fd_ < 0) return;
  // the serving thread must keep answering while the device goes (an erase may be in flight)
  ioctl(fd_, UI_DEV_DESTROY);
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  ::close(fd_);
  fd_ = -1;
}

void UinputWheel::move(int abs_code, int32_t value) {
  emit(fd_, EV_ABS, static_cast<uint16_t>(abs_code), value);
  emit(fd_, EV_SYN, SYN_REPORT, 0);
}

void UinputWheel::press(int key_code, bool down) {
  emit(fd_, EV_KEY, static_cast<uint16_t>(key_code), down ? 1 : 0);
  emit(fd_, EV_SYN, SYN_REPORT, 0);
}

std::vector<FfRecord> UinputWheel::records() const {
  std::lock_guard lock(mutex_);
  return records_;
}

// the kernel asks the device's maker to take each upload and erasure (the uploading process
// waits for the answer); plays, stops and settings arrive as EV_FF events
void UinputWheel::serve() {
  auto record = [&](FfRecord r) {
    r.t_ns = realtime::monotonic_ns();
    std::lock_guard lock(mutex_);
    records_.push_back(r);
  };
  while (!stop_) {
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, 2) <= 0) continue;
    input_event ev{};
    while (::read(fd_, &ev, sizeof ev) == static_cast<ssize_t>(sizeof ev)) {
      if (ev.type == EV_UINPUT && ev.code == UI_FF_UPLOAD) {
        uinput_ff_upload up{};
        up.request_id = static_cast<uint32_t>(ev.value);
        if (ioctl(fd_, UI_BEGIN_FF_UPLOAD, &up) < 0) continue;
        FfRecord r{FfRecord::kUpload, 0, up.effect.id};
        r.type = up.effect.type;
        if (up.effect.type == FF_CONSTANT) r.level = up.effect.u.constant.level;
        if (up.effect.type == FF_SPRING) {
          const ff_condition_effect& c = up.effect.u.condition[0];
          r.coeff = c.right_coeff == c.left_coeff ? c.right_coeff : int16_t{-1};
          r.centre = c.center;
        }
        record(r);  // before the answer: the uploader may look the moment it returns
        up.retval = 0;
        ioctl(fd_, UI_END_FF_UPLOAD, &up);
      } else if (ev.type == EV_UINPUT && ev.code == UI_FF_ERASE) {
        uinput_ff_erase er{};
        er.request_id = static_cast<uint32_t>(ev.value);
        if (ioctl(fd_, UI_BEGIN_FF_ERASE, &er) < 0) continue;
        record({FfRecord::kErase, 0, static_cast<int>(er.effect_id)});
        er.retval = 0;
        ioctl(fd_, UI_END_FF_ERASE, &er);
      } else if (ev.type == EV_FF && ev.code == FF_GAIN) {
        FfRecord r{FfRecord::kGain, 0};
        r.value = ev.value;
        record(r);
      } else if (ev.type == EV_FF && ev.code == FF_AUTOCENTER) {
        FfRecord r{FfRecord::kAutocenter, 0};
        r.value = ev.value;
        record(r);
      } else if (ev.type == EV_FF) {
        record({ev.value ? FfRecord::kPlay : FfRecord::kStop, 0, ev.code});
      }
    }
  }
}

}  // namespace pcisim::clients::testing
