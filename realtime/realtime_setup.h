#pragma once
// Asks for real-time scheduling and locked memory; falls back quietly when not permitted.
#include <string>

namespace pcisim::realtime {

struct RealtimeResult {
  bool fifo = false;    // SCHED_FIFO granted to the calling thread
  bool locked = false;  // mlockall succeeded (process-wide)
};

// call from the thread that should run real-time
bool try_sched_fifo(int priority);
bool try_mlockall();

// asks the kernel (PM QoS, /dev/cpu_dma_latency) to keep idle CPUs within latency_us of waking,
// so an idle core polls instead of halting and the 1 kHz wake-up is not delayed by a deep idle
// state (in a VM: a halted vCPU). Holds while the returned object lives; quiet when not permitted.
class CpuLatencyRequest {
 public:
  explicit CpuLatencyRequest(int latency_us);
  ~CpuLatencyRequest();
  CpuLatencyRequest(const CpuLatencyRequest&) = delete;
  CpuLatencyRequest& operator=(const CpuLatencyRequest&) = delete;
  bool granted() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
};
std::string describe(const RealtimeResult& r);

}  // namespace pcisim::realtime
