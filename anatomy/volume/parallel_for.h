#pragma once
// Work items 0..n-1 shared over threads (the caller's and threads - 1 more), each taken by the
// next free thread; each item must write its own data only. The volume painters and filters use it.
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace pcisim::anatomy {

template <typename F>
void parallel_for(int64_t n, int threads, const F& f) {
  std::atomic<int64_t> next{0};
  auto work = [&] {
    for (int64_t i; (i = next.fetch_add(1)) < n;) f(i);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::min<int64_t>(threads, n); ++t) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
}

}  // namespace pcisim::anatomy
