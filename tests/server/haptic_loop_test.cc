// The haptic thread as the server runs it: 1 kHz ticks, no allocation inside the loop.
#include "server/haptic_loop.h"

#include <gtest/gtest.h>

#include <thread>

#include "server/realtime/clock.h"
#include "tests/common/counting_new.h"


namespace pcisim::server {
namespace {

TEST(HapticLoop, TicksWithoutAllocatingAndAnswersTheNewestSample) {
  SharedState state;
  HapticLoopConfig config;
  long allocations = -1;
  std::thread haptic([&] {
    pcisim::testing::AllocationCount count;
    run_haptic_loop(config, state);
    allocations = count.allocations();
  });
  // feed it an instrument and a model while it runs, as the other threads would
  for (int i = 0; i < 300; ++i) {
    InstrumentSlot& slot = state.instrument_for_haptics.write_slot();
    slot.seq = i;
    slot.sample.received_us = monotonic_us();
    state.instrument_for_haptics.publish();
    if (i % 33 == 0) {
      physics::LocalForceModel& m = state.force_model.write_slot();
      m.made_utime = monotonic_us();
      m.valid_for_us = 66'667;
      m.f0_n = 0.5;
      state.force_model.publish();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ForceSlot out;
    while (state.forces.pop(out)) EXPECT_LE(out.instrument_seq, i);
  }
  state.stop = true;
  haptic.join();
  EXPECT_EQ(allocations, 0) << "the loop allocated";
  // the rate itself is checked in the serial integration tests; here only that it ticked
  EXPECT_GT(state.haptic.iterations.load(), 100);
  EXPECT_EQ(state.haptic.period_ns.count(), state.haptic.iterations.load() - 1);
}

}  // namespace
}  // namespace pcisim::server
