#include "xray/projectors/row_pool.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>

namespace pcisim::xray {

RowPool::RowPool(int threads) {
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  workers_.reserve(threads - 1);
  // a worker inherits the nice value of the thread that made the pool: one made while a scene is
  // built below the loops' priority (the next scene's, on the server's builder thread) would keep
  // it for good, so each takes the main thread's (best effort: lowering needs CAP_SYS_NICE)
  const int nice = ::getpriority(PRIO_PROCESS, static_cast<id_t>(::getpid()));
  for (int t = 1; t < threads; ++t)
    workers_.emplace_back([this, nice] {
      ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), nice);
      work();
    });
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
  {
    std::lock_guard lock(mutex_);
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
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
    }
    drain();
    {
      std::lock_guard lock(mutex_);
      --busy_;
    }
    done_.notify_one();
  }
}

}  // namespace pcisim::xray
