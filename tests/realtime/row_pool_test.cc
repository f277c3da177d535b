// The row pool's workers run a job at the nice value of the thread that gave it (issue #36: a
// scene built below the loops' priority projects its background there, and the same pool's
// frames later run at the x-ray thread's).
#include "realtime/row_pool.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace pcisim::realtime {
namespace {

int own_nice() {
  return ::getpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()));
}

// the nice value each row ran at; every row once
std::vector<int> niceness_of_rows(RowPool& pool, int rows) {
  std::vector<int> seen(rows, -100);
  std::atomic<int> calls{0}, by_workers{0};
  const std::thread::id caller = std::this_thread::get_id();
  auto row = [&](int r) {
    seen[r] = own_nice();
    ++calls;
    if (std::this_thread::get_id() != caller) {
      ++by_workers;
      return;
    }
    // the caller holds its first row until a worker has taken one (else the test would see the
    // caller alone); 10 s at most
    for (int i = 0; i < 10000 && by_workers.load() == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  };
  pool.for_each_row(rows, row);
  EXPECT_EQ(calls.load(), rows);
  EXPECT_GT(by_workers.load(), 0);
  return seen;
}

TEST(RowPool, WorkersRunAJobAtTheCallersNiceValue) {
  const int base = own_nice();
  RowPool pool(2);
  ASSERT_EQ(pool.threads(), 2);
  for (int n : niceness_of_rows(pool, 16)) EXPECT_EQ(n, base);

  // a builder thread below the loops gives the same pool a job: every row runs at its value
  const int lowered = std::min(base + 7, 19);
  if (lowered == base) GTEST_SKIP() << "the test runs at nice " << base << ": nothing lower to give";
  std::vector<int> from_builder;
  bool can_raise = false;  // raising a thread's priority back needs CAP_SYS_NICE (or RLIMIT_NICE)
  std::thread builder([&] {
    ASSERT_EQ(::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), lowered), 0);
    from_builder = niceness_of_rows(pool, 16);
    can_raise = ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), base) == 0;
  });
  builder.join();
  ASSERT_EQ(from_builder.size(), 16u);
  for (int n : from_builder) EXPECT_EQ(n, lowered);

  // and the next job from the first thread runs at its value again, where raising is permitted
  // (elsewhere the workers stay lowered, as a pool made on the builder thread would)
  const std::vector<int> again = niceness_of_rows(pool, 16);
  if (can_raise) {
    for (int n : again) EXPECT_EQ(n, base);
  }
}

}  // namespace
}  // namespace pcisim::realtime
