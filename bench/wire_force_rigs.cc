// The wire-force rigs' shared pieces (wire_force_rigs.h).
#include "bench/wire_force_rigs.h"

#include <algorithm>

#include "bench/bench_stats.h"

namespace pcisim::bench::wire_force {

StepCost step_cost(std::vector<double> step_ms, std::vector<int> substeps) {
  StepCost c;
  if (step_ms.empty()) return c;
  c.ms_p50 = percentile(step_ms, 0.5);
  c.ms_p99 = percentile(step_ms, 0.99);
  std::vector<double> s(substeps.begin(), substeps.end());
  c.substeps_p50 = static_cast<int>(percentile(s, 0.5));
  c.substeps_max = *std::max_element(substeps.begin(), substeps.end());
  return c;
}

}  // namespace pcisim::bench::wire_force
