// Proves the 1 kHz tick allocates nothing: global operator new is replaced in this test binary
// and counts the allocations made by the calling thread.
#include <gtest/gtest.h>

#include <cstdlib>
#include <new>

#include "haptics/force_evaluator.h"

namespace {
thread_local bool g_counting = false;
thread_local long g_allocations = 0;
}  // namespace

void* operator new(std::size_t n) {
  if (g_counting) ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace pcisim::haptics {
namespace {

TEST(NoAllocation, CounterSeesAnAllocation) {
  g_allocations = 0;
  g_counting = true;
  void* p = ::operator new(16);  // a direct call, which the compiler may not elide
  g_counting = false;
  ::operator delete(p);
  EXPECT_EQ(g_allocations, 1) << "the counting hook works";
}

TEST(NoAllocation, TenThousandTicksAllocateNothing) {
  for (Interpolation mode : {Interpolation::kLocalModel, Interpolation::kZeroOrderHold, Interpolation::kLinearExtrapolation}) {
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
    g_allocations = 0;
    g_counting = true;
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
    g_counting = false;
    EXPECT_EQ(g_allocations, 0) << "mode " << static_cast<int>(mode);
  }
}

}  // namespace
}  // namespace pcisim::haptics
