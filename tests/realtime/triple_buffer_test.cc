#include "realtime/triple_buffer.h"

#include <gtest/gtest.h>

#include <array>
#include <thread>

namespace pcisim::realtime {
namespace {

// a value that is torn if any of its words disagree
struct Block {
  std::array<int64_t, 32> words{};
};

TEST(TripleBuffer, ReaderSeesOnlyWholeValuesInOrderUnderConcurrentUse) {
  realtime::TripleBuffer<Block> buffer;
  constexpr int64_t kWrites = 200000;
  std::thread writer([&] {
    for (int64_t v = 1; v <= kWrites; ++v) {
      buffer.write_slot().words.fill(v);
      buffer.publish();
    }
  });
  int64_t last = 0, fresh = 0;
  while (last < kWrites) {
    if (!buffer.refresh()) continue;
    const Block& b = buffer.read_slot();
    for (int64_t w : b.words) ASSERT_EQ(w, b.words[0]) << "torn read";
    ASSERT_GT(b.words[0], last) << "a refresh must deliver a newer value";
    last = b.words[0];
    ++fresh;
  }
  writer.join();
  EXPECT_EQ(last, kWrites) << "the newest value always arrives";
  EXPECT_GT(fresh, 0);
}

TEST(TripleBuffer, RefreshWithoutPublishKeepsTheValue) {
  realtime::TripleBuffer<int> buffer(7);
  EXPECT_FALSE(buffer.refresh());
  EXPECT_EQ(buffer.read_slot(), 7);
  buffer.write_slot() = 8;
  buffer.publish();
  buffer.write_slot() = 9;
  buffer.publish();
  EXPECT_TRUE(buffer.refresh());
  EXPECT_EQ(buffer.read_slot(), 9) << "latest wins";
  EXPECT_FALSE(buffer.refresh());
  EXPECT_EQ(buffer.read_slot(), 9);
}

}  // namespace
}  // namespace pcisim::realtime
