#pragma once
// A latency histogram of fixed bins, filled without allocating (the bridge's 1 kHz loop and its
// receive thread each own one): 10 us bins to 20 ms, beyond that one overflow bin (its values
// still count towards max_us). Percentiles are the upper edge of the bin that holds them.
#include <algorithm>
#include <array>
#include <cstdint>

namespace pcisim::clients {

class LatencyHistogram {
 public:
  static constexpr double kBinUs = 10.0;
  static constexpr int kBins = 2000;  // 20 ms

  void add(double us) {
    if (!(us >= 0.0)) us = 0.0;
    // beyond the bins (or infinite) goes to the overflow bin before any cast to int
    const int bin = us >= kBins * kBinUs ? kBins : static_cast<int>(us / kBinUs);
    ++counts_[bin];
    ++count_;
    max_us_ = std::max(max_us_, us);
  }
  int64_t count() const { return count_; }
  double max_us() const { return max_us_; }
  // p in [0, 1]: the upper edge of the bin holding the p-quantile; max_us() for the overflow bin;
  // 0 when empty
  double percentile_us(double p) const {
    if (count_ == 0) return 0.0;
    const auto rank = static_cast<int64_t>(std::max<double>(1.0, p * count_ + 0.5));
    int64_t seen = 0;
    for (int b = 0; b < kBins; ++b) {
      seen += counts_[b];
      if (seen >= rank) return std::min((b + 1) * kBinUs, max_us_);
    }
    return max_us_;
  }

 private:
  std::array<int64_t, kBins + 1> counts_{};
  int64_t count_ = 0;
  double max_us_ = 0.0;
};

}  // namespace pcisim::clients
