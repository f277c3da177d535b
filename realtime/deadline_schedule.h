#pragma once
// Absolute deadlines for a fixed-rate loop: deadline k is start + k * period. When an iteration
// ends more than a period past its deadline, the missed deadlines are skipped and counted, so a
// slow iteration never causes a burst of catch-up iterations.
#include <cstdint>
#include <stdexcept>

namespace pcisim::realtime {

class DeadlineSchedule {
 public:
  // period_ns must be > 0 (std::invalid_argument otherwise)
  DeadlineSchedule(int64_t start_ns, int64_t period_ns) : deadline_ns_(start_ns + period_ns), period_ns_(period_ns) {
    if (period_ns <= 0) throw std::invalid_argument("DeadlineSchedule: the period must be > 0 ns");
  }

  int64_t deadline_ns() const { return deadline_ns_; }
  int64_t period_ns() const { return period_ns_; }

  // the iteration woken at deadline_ns() finished at done_ns; returns how many deadlines it skipped
  int64_t complete(int64_t done_ns) {
    int64_t missed = 0;
    if (done_ns - deadline_ns_ > period_ns_) {
      missed = (done_ns - deadline_ns_) / period_ns_;
      deadline_ns_ += missed * period_ns_;
    }
    deadline_ns_ += period_ns_;
    return missed;
  }

 private:
  int64_t deadline_ns_;
  int64_t period_ns_;
};

}  // namespace pcisim::realtime
