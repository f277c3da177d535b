// The wire-force rigs' shared pieces (wire_force_rigs.h).
#include "bench/wire_force_rigs.h"

#include <fmt/format.h>

#include <algorithm>

#include "bench/bench_stats.h"

namespace pcisim::bench::wire_force {

namespace {
physics::RodContactScheme g_scheme = physics::RodContactScheme::kSolve;
}  // namespace

physics::RodContactScheme contact_scheme() {
  return g_scheme;
}

void set_contact_scheme(physics::RodContactScheme scheme) {
  g_scheme = scheme;
}

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

std::string cost_json(const StepCost& c) {
  return fmt::format(R"("step_ms_p50": {:.3f}, "step_ms_p99": {:.3f}, "substeps_p50": {}, "substeps_max": {})",
                     c.ms_p50, c.ms_p99, c.substeps_p50, c.substeps_max);
}

}  // namespace pcisim::bench::wire_force
