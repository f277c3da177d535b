// PbdSystem::step allocates nothing once finalize() has sized its buffers, for both solvers,
// with driven particles moving and clusters matching.
#include <gtest/gtest.h>

#include <cmath>

#include "physics/pbd/procedural_ventricle.h"
#include "realtime/allocation_count.h"

namespace pcisim::physics::pbd {
namespace {

TEST(PbdNoAllocation, StepAllocatesNothing) {
  VentricleSpec spec;
  spec.spacing_m = 0.006;  // a small ventricle: the test is about allocation, not accuracy
  Ventricle v = build_ventricle(spec);
  for (SolverKind solver : {SolverKind::kGaussSeidel, SolverKind::kJacobi}) {
    PbdParams p;
    p.solver = solver;
    p.substeps = 2;
    p.iterations = 3;
    p.sor_w = 1.5;
    p.damping_per_s = 5;
    v.system.step(1.0 / 30, p);  // the first step may touch lazily sized state
    long allocations = -1;
    {
      pcisim::realtime::AllocationCount count;
      for (int k = 0; k < 20; ++k) {
        const double squeeze = 1.0 - 0.1 * std::sin(0.4 * k);
        for (int i : v.driven) v.system.set_driven_target(i, v.rest_m.col(i) * squeeze);
        v.system.step(1.0 / 30, p);
      }
      allocations = count.allocations();
    }
    EXPECT_EQ(allocations, 0) << "solver " << static_cast<int>(solver);
  }
}

}  // namespace
}  // namespace pcisim::physics::pbd
