#include "server/realtime/realtime_setup.h"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

namespace pcisim::server {

bool try_sched_fifo(int priority) {
  sched_param sp{};
  sp.sched_priority = priority;
  return pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
}

bool try_mlockall() { return mlockall(MCL_CURRENT | MCL_FUTURE) == 0; }

std::string describe(const RealtimeResult& r) {
  return std::string(r.fifo ? "SCHED_FIFO" : "SCHED_OTHER (FIFO not permitted)") +
         (r.locked ? ", memory locked" : ", memory not locked");
}

}  // namespace pcisim::server
