#pragma once
// A fixed pool of std::threads that runs "for each row" jobs: rows are handed out through an
// atomic counter, the calling thread works too, the workers at its nice value. Threads start once;
// a job allocates nothing.
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

namespace pcisim::realtime {

class RowPool {
 public:
  // threads <= 0: std::thread::hardware_concurrency(); the caller counts as one of them
  explicit RowPool(int threads);
  ~RowPool();
  RowPool(const RowPool&) = delete;
  RowPool& operator=(const RowPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }

  // calls fn(row) once for each row in [0, rows), spread over the pool; returns when all are done
  template <class Fn>
  void for_each_row(int rows, Fn& fn) {
    run(
        rows, [](void* ctx, int row) { (*static_cast<Fn*>(ctx))(row); }, &fn);
  }

 private:
  using RowFn = void (*)(void*, int);
  void run(int rows, RowFn fn, void* ctx);
  void work();
  void drain();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  uint64_t generation_ = 0;
  int busy_ = 0;
  bool stop_ = false;
  RowFn fn_ = nullptr;
  void* ctx_ = nullptr;
  int rows_ = 0;
  int nice_ = 0;  // the caller's nice value: the workers run its job at it
  std::atomic<int> next_{0};
};

}  // namespace pcisim::realtime
