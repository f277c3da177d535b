#pragma once
// The statistics every benchmark report uses, defined once: nearest-rank percentiles.
#include <algorithm>
#include <cmath>
#include <vector>

namespace pcisim::bench {

// the smallest sample with at least q of the samples at or below it (nearest rank); 0 when empty
inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double rank = std::ceil(q * static_cast<double>(v.size()));
  const size_t i = rank < 1 ? 0 : static_cast<size_t>(rank) - 1;
  return v[std::min(i, v.size() - 1)];
}

}  // namespace pcisim::bench
