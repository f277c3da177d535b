#pragma once
// Asks for real-time scheduling and locked memory; falls back quietly when not permitted.
#include <string>

namespace pcisim::server {

struct RealtimeResult {
  bool fifo = false;    // SCHED_FIFO granted to the calling thread
  bool locked = false;  // mlockall succeeded (process-wide)
};

// call from the thread that should run real-time
bool try_sched_fifo(int priority);
bool try_mlockall();
std::string describe(const RealtimeResult& r);

}  // namespace pcisim::server
