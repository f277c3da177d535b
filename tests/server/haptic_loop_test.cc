// The haptic thread as the server runs it: 1 kHz ticks, no allocation inside the loop.
#include "server/haptic_loop.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

#include "realtime/clock.h"
#include "realtime/allocation_count.h"

namespace pcisim::server {
namespace {

TEST(HapticLoop, TicksWithoutAllocatingAndAnswersTheNewestSample) {
  SharedState state;
  HapticLoopConfig config;
  long allocations = -1;
  int64_t newest_seq = -1;
  double peak_n = 0.0;
  std::thread haptic([&] {
    pcisim::realtime::AllocationCount count;
    run_haptic_loop(config, state);
    allocations = count.allocations();
  });
  // feed it an instrument and a model while it runs, as the other threads would
  for (int i = 0; i < 600; ++i) {
    InstrumentSlot& slot = state.instrument_for_haptics.write_slot();
    slot.seq = i;
    slot.sample.received_us = realtime::monotonic_us();
    state.instrument_for_haptics.publish();
    if (i % 33 == 0) {
      physics::LocalForceModel& m = state.force_model.write_slot();
      m.made_utime = realtime::monotonic_us();
      m.valid_for_us = 1'000'000;  // a stall of the test thread must not make it stale
      m.f0_n = 0.5;
      state.force_model.publish();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ForceSlot out;
    while (state.forces.pop(out)) {
      EXPECT_LE(out.instrument_seq, i) << "never a sample not yet published";
      newest_seq = std::max(newest_seq, out.instrument_seq);
      peak_n = std::max(peak_n, out.force.axial_force_n);
    }
  }
  state.stop_haptic = true;
  haptic.join();
  EXPECT_EQ(allocations, 0) << "the loop allocated";
  // the forces answered the samples as they came (the newest seen is recent), and once the
  // 200 ms ramp-in is through the force is the model's f0, never more: the loop really evaluates
  // the model (a busy machine can stall this thread past the instrument timeout and restart the
  // ramp, so the peak is asserted, not the last value)
  EXPECT_GE(newest_seq, 550);
  EXPECT_NEAR(peak_n, 0.5, 0.01);
  EXPECT_LE(peak_n, 0.5 + 1e-12);
  // the rate itself is checked in the serial integration tests; here only that it ticked
  EXPECT_GT(state.haptic.iterations.load(), 100);
  EXPECT_EQ(state.haptic.period_ns.count(), state.haptic.iterations.load() - 1);
}

}  // namespace
}  // namespace pcisim::server
