#include "realtime/latency_histogram.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace pcisim::realtime {

int LatencyHistogram::bucket_of(int64_t value_ns) {
  if (value_ns < 256) return value_ns < 0 ? 0 : static_cast<int>(value_ns);
  const int msb = 63 - std::countl_zero(static_cast<uint64_t>(value_ns));
  const int64_t mantissa = value_ns >> (msb - 7);  // in [128, 255]
  return 256 + (msb - 8) * 128 + static_cast<int>(mantissa - 128);
}

int64_t LatencyHistogram::bucket_low_ns(int bucket) {
  if (bucket < 256) return bucket;
  const int msb = 8 + (bucket - 256) / 128;
  const int64_t mantissa = 128 + (bucket - 256) % 128;
  return mantissa << (msb - 7);
}

void LatencyHistogram::record(int64_t value_ns) {
  counts_[bucket_of(value_ns)].fetch_add(1, std::memory_order_relaxed);
  int64_t seen = max_ns_.load(std::memory_order_relaxed);
  while (value_ns > seen && !max_ns_.compare_exchange_weak(seen, value_ns, std::memory_order_relaxed)) {}
}

void LatencyHistogram::reset() {
  for (auto& c : counts_) c.store(0, std::memory_order_relaxed);
  max_ns_.store(0, std::memory_order_relaxed);
}

int64_t LatencyHistogram::count() const {
  uint64_t n = 0;
  for (const auto& c : counts_) n += c.load(std::memory_order_relaxed);
  return static_cast<int64_t>(n);
}

double LatencyHistogram::quantile_ns(double q) const {
  const int64_t n = count();
  if (n == 0) return 0.0;
  // the nearest rank, as realtime::percentile: the ceil(q n)-th smallest (1-based), at least the first
  const double r = std::ceil(std::min(std::max(q, 0.0), 1.0) * static_cast<double>(n));
  const auto rank = static_cast<uint64_t>(std::max(r, 1.0));
  uint64_t seen = 0;
  for (int b = 0; b < kBuckets; ++b) {
    seen += counts_[b].load(std::memory_order_relaxed);
    if (seen >= rank) {
      if (b < 256) return static_cast<double>(b);
      const double low = static_cast<double>(bucket_low_ns(b));
      const double high = static_cast<double>(bucket_low_ns(b + 1));
      return std::min(0.5 * (low + high), max_ns());
    }
  }
  return max_ns();
}

}  // namespace pcisim::realtime
