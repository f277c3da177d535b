#include "realtime/row_pool.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>

namespace pcisim::realtime {

RowPool::RowPool(int threads) {
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  workers_.reserve(threads - 1);
  for (int t = 1; t < threads; ++t) workers_.emplace_back([this] { work(); });
}

RowPool::~RowPool() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (auto& w : workers_) w.join();
}

void RowPool::drain() {
  for (int row = next_.fetch_add(1); row < rows_; row = next_.fetch_add(1)) fn_(ctx_, row);
}

void RowPool::run(int rows, RowFn fn, void* ctx) {
  // the workers run the job at the caller's nice value: the next scene, built below the loops'
  // priority on the server's builder thread, projects its background there too, and the same
  // pool's frames later run at the x-ray thread's (where raising a thread back is permitted:
  // CAP_SYS_NICE; else the workers stay lowered, as before, and retry each job)
  const int nice = ::getpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()));
  {
    std::lock_guard lock(mutex_);
    nice_ = nice;
    fn_ = fn;
    ctx_ = ctx;
    rows_ = rows;
    next_.store(0);
    busy_ = static_cast<int>(workers_.size());
    ++generation_;
  }
  wake_.notify_all();
  drain();
  std::unique_lock lock(mutex_);
  done_.wait(lock, [this] { return busy_ == 0; });
}

void RowPool::work() {
  uint64_t seen = 0;
  int my_nice = ::getpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()));
  for (;;) {
    int nice = 0;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      nice = nice_;
    }
    // (best effort: raising a thread's priority again needs CAP_SYS_NICE)
    if (nice != my_nice && ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), nice) == 0) my_nice = nice;
    drain();
    {
      std::lock_guard lock(mutex_);
      --busy_;
    }
    done_.notify_one();
  }
}

}  // namespace pcisim::realtime
