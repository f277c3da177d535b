#pragma once
// CLOCK_MONOTONIC helpers: every loop in the server uses this one clock.
#include <cerrno>
#include <cstdint>
#include <ctime>

namespace pcisim::realtime {

inline int64_t monotonic_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

inline int64_t monotonic_us() {
  return monotonic_ns() / 1000;
}

// sleeps until an absolute CLOCK_MONOTONIC deadline, restarting after signals (only those: any
// other error, e.g. EINVAL, returns at once rather than spinning); a deadline before the clock's
// start returns at once
inline void sleep_until_ns(int64_t deadline_ns) {
  if (deadline_ns <= 0) return;
  timespec ts{static_cast<time_t>(deadline_ns / 1'000'000'000), static_cast<long>(deadline_ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {}
}

}  // namespace pcisim::realtime
