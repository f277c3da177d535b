#pragma once
// The 1 kHz haptic thread: absolute deadlines, skip-ahead on overrun, and inside the loop no
// allocation, lock, log or LCM call — only the sleep.
#include "haptics/haptic_params.h"
#include "server/shared_state.h"

namespace pcisim::server {

struct HapticLoopConfig {
  haptics::HapticParams params;
  int64_t period_ns = 1'000'000;
  int fifo_priority = 80;
};

// runs until state.stop_haptic; returns whether SCHED_FIFO was granted
bool run_haptic_loop(const HapticLoopConfig& config, SharedState& state);

}  // namespace pcisim::server
