#pragma once
// A log-linear histogram of durations in nanoseconds: exact below 256 ns, then 128 buckets per
// power of two (under 0.8 % relative error). Recording is one relaxed atomic add, so the 1 kHz
// loop can record while another thread reads percentiles.
#include <array>
#include <atomic>
#include <cstdint>

namespace pcisim::realtime {

class LatencyHistogram {
 public:
  void record(int64_t value_ns);
  void reset();

  int64_t count() const;
  // value at quantile q in [0, 1]: the bucket (its midpoint, at most the largest sample) that holds
  // the nearest-rank sample, the ceil(q n)-th smallest, as realtime::percentile ranks; 0 when empty
  double quantile_ns(double q) const;
  double max_ns() const { return static_cast<double>(max_ns_.load(std::memory_order_relaxed)); }

  static int bucket_of(int64_t value_ns);
  static int64_t bucket_low_ns(int bucket);

 private:
  static constexpr int kBuckets = 256 + (62 - 8 + 1) * 128;
  std::array<std::atomic<uint64_t>, kBuckets> counts_{};
  std::atomic<int64_t> max_ns_{0};
};

}  // namespace pcisim::realtime
