#include "realtime/realtime_setup.h"

#include <pthread.h>
#include <sched.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>

namespace pcisim::realtime {

bool try_sched_fifo(int priority) {
  sched_param sp{};
  sp.sched_priority = priority;
  return pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
}

// once locked, MCL_FUTURE keeps every later mapping locked: a second call (the next scene's
// pipeline) would only walk the whole process again
bool try_mlockall() {
  static std::atomic<bool> locked{false};
  if (locked.load()) return true;
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) return false;
  locked = true;
  return true;
}

CpuLatencyRequest::CpuLatencyRequest(int latency_us) {
  if (latency_us < 0) return;
  fd_ = ::open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
  const int32_t value = latency_us;
  if (fd_ >= 0 && ::write(fd_, &value, sizeof value) != static_cast<ssize_t>(sizeof value)) {
    ::close(fd_);
    fd_ = -1;
  }
}

CpuLatencyRequest::~CpuLatencyRequest() {
  if (fd_ >= 0) ::close(fd_);  // closing withdraws the request
}

std::string describe(const RealtimeResult& r) {
  return std::string(r.fifo ? "SCHED_FIFO" : "SCHED_OTHER (FIFO not permitted)") +
         (r.locked ? ", memory locked" : ", memory not locked");
}

}  // namespace pcisim::realtime
