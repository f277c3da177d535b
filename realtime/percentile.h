#pragma once
// The one percentile of the project: every report's "p50", "p95" and "p99", every benchmark's
// median and every quantile a model takes of its samples mean this, so the figures compare.
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <vector>

namespace pcisim::realtime {

// the q-quantile by nearest rank: the smallest sample with at least a fraction q of the samples
// at or below it, i.e. the ceil(q n)-th smallest of n (1-based; q <= 0 gives the smallest, q >= 1
// the largest; the median of an even count is the lower middle one). No interpolation: the
// result is always one of the samples. NaN when there are none; a NaN q is taken as 0. Reorders v
// (nth_element, O(n)).
template <class T>
T percentile_in_place(std::span<T> v, double q) {
  if (v.empty()) return std::numeric_limits<T>::quiet_NaN();
  if (!(q > 0.0)) q = 0.0;  // NaN too: no NaN reaches the cast below
  const double rank = std::ceil(std::min(q, 1.0) * static_cast<double>(v.size()));
  const size_t k = rank <= 1 ? 0 : std::min(static_cast<size_t>(rank) - 1, v.size() - 1);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// the same on a copy (the caller's samples keep their order)
template <class T>
T percentile(std::vector<T> v, double q) {
  return percentile_in_place(std::span<T>(v), q);
}

}  // namespace pcisim::realtime
