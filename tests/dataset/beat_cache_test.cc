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

// a make that fails is not kept: a job that waited for it, or asks after it, makes its own (the
// failure stays the failing job's, as without the cache)
TEST(BeatCache, AFailedMakeIsNotKeptAndTheWaitersMakeTheirOwn) {
  BeatCache cache;
  std::atomic<bool> making{false};
  std::atomic<int> makes{0};
  std::thread failing([&] {
    EXPECT_THROW(cache.get("k",
                           [&]() -> Kept {
                             making = true;
                             std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the other asks meanwhile
                             throw std::runtime_error("no memory for the changes");
                           }),
                 std::runtime_error);
  });
  while (!making) std::this_thread::yield();
  const Kept mine = cache.get("k", [&] {
    ++makes;
    return some_beat();
  });
  failing.join();
  EXPECT_NE(mine, nullptr);
  EXPECT_EQ(makes.load(), 1);
  EXPECT_EQ(cache.get("k",
                      [&]() -> Kept {
                        ADD_FAILURE() << "made again while held";
                        return nullptr;
                      }),
            mine);
}

// a beat is kept only while a job holds it: let go by all, the next ask makes it again
TEST(BeatCache, ABeatNoJobHoldsIsMadeAgain) {
  BeatCache cache;
  int makes = 0;
  auto make = [&] {
    ++makes;
    return some_beat();
  };
  Kept held = cache.get("72 bpm", make);
  std::weak_ptr<const SharedBeat> watch = held;
  EXPECT_EQ(cache.get("72 bpm", make), held);
  EXPECT_EQ(makes, 1);
  held.reset();
  EXPECT_TRUE(watch.expired()) << "the cache holds no beat itself";
  cache.get("72 bpm", make);
  EXPECT_EQ(makes, 2);
}

}  // namespace
}  // namespace pcisim::dataset
