#include "realtime/deadline_schedule.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include "realtime/clock.h"

namespace pcisim::realtime {
namespace {

constexpr int64_t kMs = 1'000'000;

TEST(DeadlineSchedule, OnTimeIterationsKeepAbsoluteDeadlines) {
  realtime::DeadlineSchedule s(0, kMs);
  for (int k = 1; k <= 1000; ++k) {
    EXPECT_EQ(s.deadline_ns(), k * kMs);
    EXPECT_EQ(s.complete(s.deadline_ns() + kMs / 3), 0);  // work done within the period
  }
}

TEST(DeadlineSchedule, OverrunIsCountedAndSkippedNotCaughtUpInABurst) {
  const int64_t period = 33 * kMs;
  realtime::DeadlineSchedule s(0, period);
  const int64_t woke = s.deadline_ns();
  const int64_t done = woke + 100 * kMs;  // a physics step three periods long
  EXPECT_EQ(s.complete(done), 3);
  EXPECT_GT(s.deadline_ns(), done) << "the next deadline lies in the future: no burst";
  EXPECT_LE(s.deadline_ns() - done, period);
  EXPECT_EQ((s.deadline_ns() - woke) % period, 0) << "deadlines stay on the original grid";
}

}  // namespace
TEST(DeadlineSchedule, ZeroOrNegativePeriodIsRefused) {
  EXPECT_THROW(realtime::DeadlineSchedule(0, 0), std::invalid_argument);
  EXPECT_THROW(realtime::DeadlineSchedule(0, -5), std::invalid_argument);
}

TEST(Clock, DeadlinesInThePastOrBeforeTheClockStartReturnAtOnce) {
  const int64_t t0 = realtime::monotonic_ns();
  realtime::sleep_until_ns(-1'000'000'000);  // EINVAL territory: must not spin
  realtime::sleep_until_ns(t0 - 1'000'000);
  EXPECT_LT(realtime::monotonic_ns() - t0, 50'000'000);
}

}  // namespace pcisim::realtime
