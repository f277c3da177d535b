// The row pool's workers run a job at the nice value of the thread that gave it (issue #36: a
// scene built below the loops' priority projects its background there, and the same pool's
// frames later run at the x-ray thread's).
#include "xray/projectors/row_pool.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace pcisim::xray {
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
    // long enough that the worker takes rows too
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    seen[r] = own_nice();
    ++calls;
    if (std::this_thread::get_id() != caller) ++by_workers;
  };
  pool.for_each_row(rows, row);
  EXPECT_EQ(calls.load(), rows);
  EXPECT_GT(by_workers.load(), 0);  // else the test would only see the caller
  return seen;
}

TEST(RowPool, WorkersRunAJobAtTheCallersNiceValue) {
  const int base = own_nice();
  RowPool pool(2);
  ASSERT_EQ(pool.threads(), 2);
  for (int n : niceness_of_rows(pool, 16)) EXPECT_EQ(n, base);

  // a builder thread below the loops gives the same pool a job: every row runs at its value
  const int lowered = std::min(base + 7, 19);
  std::vector<int> from_builder;
  std::thread builder([&] {
    ASSERT_EQ(::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), lowered), 0);
    from_builder = niceness_of_rows(pool, 16);
  });
  builder.join();
  ASSERT_EQ(from_builder.size(), 16u);
  for (int n : from_builder) EXPECT_EQ(n, lowered);

  // and the next job from the first thread runs at its value again (raising a thread back needs
  // CAP_SYS_NICE: as root, as in CI; elsewhere the worker may stay lowered)
  const std::vector<int> again = niceness_of_rows(pool, 16);
  if (::geteuid() == 0) {
    for (int n : again) EXPECT_EQ(n, base);
  }
}

}  // namespace
}  // namespace pcisim::xray
