// The beating background shared by a dataset's jobs (dataset/sample/anatomy_cache.h): made once
// per key however many jobs ask at once, each key its own, and a make that fails is not kept (the
// next ask makes it again).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "dataset/sample/anatomy_cache.h"

namespace pcisim::dataset {
namespace {

using Kept = BeatCache::Kept;

Kept some_beat() {
  return std::make_shared<const SharedBeat>();
}

TEST(BeatCache, EightJobsAskingAtOnceShareOneWrite) {
  BeatCache cache;
  std::atomic<int> writes{0};
  std::vector<Kept> got(8);
  std::vector<std::thread> jobs;
  for (int j = 0; j < 8; ++j)
    jobs.emplace_back([&, j] {
      got[j] = cache.get("72 bpm", [&] {
        ++writes;
        std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the others ask meanwhile
        return some_beat();
      });
    });
  for (auto& t : jobs) t.join();
  EXPECT_EQ(writes.load(), 1);
  for (const Kept& c : got) EXPECT_EQ(c, got.front());
  ASSERT_NE(got.front(), nullptr);
  // another key is written on its own; the first stays kept
  const Kept other = cache.get("90 bpm", some_beat);
  EXPECT_NE(other, got.front());
  EXPECT_EQ(cache.get("72 bpm",
                      [&]() -> Kept {
                        ADD_FAILURE() << "written again";
                        return nullptr;
                      }),
            got.front());
}

TEST(BeatCache, AFailedWriteReachesItsWaitersAndIsNotKept) {
  BeatCache cache;
  std::atomic<bool> writing{false};
  std::thread writer([&] {
    EXPECT_THROW(cache.get("k",
                           [&]() -> Kept {
                             writing = true;
                             std::this_thread::sleep_for(std::chrono::milliseconds(50));
                             throw std::runtime_error("no memory for the changes");
                           }),
                 std::runtime_error);
  });
  while (!writing) std::this_thread::yield();
  // a job that asked while it was written sees the failure (or, coming after it, writes itself)
  try {
    const Kept c = cache.get("k", some_beat);
    EXPECT_NE(c, nullptr);
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "no memory for the changes");
  }
  writer.join();
  int writes = 0;
  const Kept again = cache.get("k", [&] {
    ++writes;
    return some_beat();
  });
  EXPECT_NE(again, nullptr);
  EXPECT_LE(writes, 1);
  // kept now
  EXPECT_EQ(cache.get("k",
                      [&]() -> Kept {
                        ADD_FAILURE() << "written again";
                        return nullptr;
                      }),
            again);
}

}  // namespace
}  // namespace pcisim::dataset
