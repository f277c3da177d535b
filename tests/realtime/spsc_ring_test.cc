#include "realtime/spsc_ring.h"

#include <gtest/gtest.h>

#include <thread>

namespace pcisim::realtime {
namespace {

TEST(SpscRing, ReportsFullAndEmpty) {
  realtime::SpscRing<int, 4> ring;
  int v = 0;
  EXPECT_FALSE(ring.pop(v));
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(ring.push(i));
  EXPECT_FALSE(ring.push(99)) << "a full ring refuses instead of overwriting";
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(ring.pop(v));
    EXPECT_EQ(v, i);
  }
  EXPECT_FALSE(ring.pop(v));
}

TEST(SpscRing, DeliversEverythingInOrderAcrossThreads) {
  realtime::SpscRing<int64_t, 64> ring;
  constexpr int64_t kCount = 500000;
  std::thread producer([&] {
    for (int64_t i = 0; i < kCount; ++i)
      while (!ring.push(i)) std::this_thread::yield();
  });
  int64_t expected = 0, v = 0;
  while (expected < kCount) {
    if (!ring.pop(v)) continue;
    ASSERT_EQ(v, expected);
    ++expected;
  }
  producer.join();
}

}  // namespace
}  // namespace pcisim::realtime
