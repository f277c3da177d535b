#pragma once
// A mutex with priority inheritance (PTHREAD_PRIO_INHERIT): a low-priority thread holding it runs
// at the priority of the highest thread waiting for it, so a SCHED_FIFO thread (the LCM send
// thread that carries the 1 kHz force commands) never waits behind a preempted ordinary one.
// std::mutex cannot ask for it. Meets BasicLockable (std::lock_guard works with it).
#include <pthread.h>

namespace pcisim::realtime {

class PiMutex {
 public:
  PiMutex() {
    pthread_mutexattr_t a;
    pthread_mutexattr_init(&a);
    // (where the protocol is not supported the mutex is an ordinary one)
    pthread_mutexattr_setprotocol(&a, PTHREAD_PRIO_INHERIT);
    pthread_mutex_init(&m_, &a);
    pthread_mutexattr_destroy(&a);
  }
  ~PiMutex() { pthread_mutex_destroy(&m_); }
  PiMutex(const PiMutex&) = delete;
  PiMutex& operator=(const PiMutex&) = delete;
  void lock() { pthread_mutex_lock(&m_); }
  void unlock() { pthread_mutex_unlock(&m_); }

 private:
  pthread_mutex_t m_;
};

}  // namespace pcisim::realtime
