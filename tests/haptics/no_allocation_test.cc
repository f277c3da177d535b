// Proves the 1 kHz tick allocates nothing (realtime/allocation_count.h counts this thread's
// allocations).
#include <gtest/gtest.h>

#include "haptics/force_evaluator.h"
#include "realtime/allocation_count.h"

namespace pcisim::haptics {
namespace {

TEST(NoAllocation, CounterSeesAnAllocation) {
  long n = 0;
  {
    pcisim::realtime::AllocationCount count;
    void* p = ::operator new(16);  // a direct call, which the compiler may not elide
    ::operator delete(p);
    n = count.allocations();
  }
  EXPECT_EQ(n, 1) << "the counting hook works";
}

TEST(NoAllocation, TenThousandTicksAllocateNothing) {
  for (Interpolation mode :
       {Interpolation::kLocalModel, Interpolation::kZeroOrderHold, Interpolation::kLinearExtrapolation}) {
    HapticParams p;
    p.interpolation = mode;
    ForceEvaluator e(p);
    physics::LocalForceModel m;
    m.valid_for_us = 66'667;
    m.f0_n = 0.5;
    m.k_n_per_m = 100;
    m.b_n_s_per_m = -3;  // active: exercise the passivity controller too
    InstrumentSample s;
    int64_t t = 1'000'000;
    pcisim::realtime::AllocationCount count;
    for (int i = 0; i < 10000; ++i) {
      t += 1000;
      if (i % 33 == 0) {
        m.made_utime = t;
        e.set_model(m, t);
      }
      s.received_us = i < 9000 ? t : s.received_us;  // the instrument falls silent at the end
      s.insertion_m = 1e-5 * i;
      s.insertion_rate_m_per_s = 0.01;
      e.tick(s, t);
    }
    EXPECT_EQ(count.allocations(), 0) << "mode " << static_cast<int>(mode);
  }
}

}  // namespace
}  // namespace pcisim::haptics
