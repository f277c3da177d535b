#pragma once
// The one percentile of the project: every report's "p50", "p95" and "p99" and every benchmark's
// median mean percentile() below, so the figures compare (LatencyHistogram ranks its buckets the
// same way); the models' robust estimators take the upper median, the same selection at a stated
// rank. The one other quantile is an area-weighted one (a surface distance's 95 %, in
// modeling/evaluation/lumen_scores.cc), which weights samples and so is not a rank of them.
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <vector>

namespace pcisim::realtime {

// the k-th smallest of v (0-based, k < v.size()): the one selection the rank rules below share.
// Reorders v (nth_element, O(n)).
template <class T>
T kth_smallest_in_place(std::span<T> v, size_t k) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// the q-quantile by nearest rank: the smallest sample with at least a fraction q of the samples
// at or below it, i.e. the ceil(q n)-th smallest of n (1-based; q <= 0 gives the smallest, q >= 1
// the largest; the median of an even count is the lower middle one). No interpolation: the
// result is always one of the samples. NaN when there are none; a NaN q is taken as 0. Reorders v.
template <class T>
T percentile_in_place(std::span<T> v, double q) {
  if (v.empty()) return std::numeric_limits<T>::quiet_NaN();
  if (!(q > 0.0)) q = 0.0;  // NaN too: no NaN reaches the cast below
  const double rank = std::ceil(std::min(q, 1.0) * static_cast<double>(v.size()));
  const size_t k = rank <= 1 ? 0 : std::min(static_cast<size_t>(rank) - 1, v.size() - 1);
  return kth_smallest_in_place(v, k);
}

// the robust estimators inside the models (a cross-section's ray radii, a median filter's window,
// a DICOM series' slice gaps, a fit's trimming scale) take the upper median: the (floor(n/2)+1)-th
// smallest of n, i.e. the middle sample of an odd count (percentile 0.5 above) and the upper of
// the two middle ones of an even count (a cross-section's 32 rays). Not used for any reported
// figure. NaN when there are none. Reorders v.
template <class T>
T upper_median_in_place(std::span<T> v) {
  if (v.empty()) return std::numeric_limits<T>::quiet_NaN();
  return kth_smallest_in_place(v, v.size() / 2);
}

// the same on a copy (the caller's samples keep their order)
template <class T>
T percentile(std::vector<T> v, double q) {
  return percentile_in_place(std::span<T>(v), q);
}

}  // namespace pcisim::realtime
