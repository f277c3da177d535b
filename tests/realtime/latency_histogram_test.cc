#include "realtime/latency_histogram.h"
#include "realtime/percentile.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace pcisim::realtime {
namespace {

TEST(LatencyHistogram, BucketsCoverEveryValueMonotonically) {
  int previous = -1;
  for (int64_t v : {0LL, 1LL, 255LL, 256LL, 258LL, 1000LL, 1'000'000LL, 1'000'000'000LL, (1LL << 62)}) {
    const int b = realtime::LatencyHistogram::bucket_of(v);
    EXPECT_GT(b, previous);
    EXPECT_LE(realtime::LatencyHistogram::bucket_low_ns(b), v);
    EXPECT_GT(realtime::LatencyHistogram::bucket_low_ns(b + 1), v);
    previous = b;
  }
}

TEST(LatencyHistogram, QuantilesMatchSortedSamplesWithinResolution) {
  std::mt19937_64 rng(3);
  std::lognormal_distribution<double> dist(13.8, 0.4);  // around 1 ms in ns, like a haptic period
  realtime::LatencyHistogram h;
  std::vector<int64_t> samples;
  for (int i = 0; i < 100000; ++i) {
    samples.push_back(static_cast<int64_t>(dist(rng)));
    h.record(samples.back());
  }
  std::sort(samples.begin(), samples.end());
  EXPECT_EQ(h.count(), 100000);
  for (double q : {0.5, 0.9, 0.99, 0.999}) {
    const double exact = static_cast<double>(percentile(std::vector<int64_t>(samples), q));  // the one rank
    EXPECT_NEAR(h.quantile_ns(q), exact, 0.01 * exact) << "q=" << q;
  }
  EXPECT_EQ(h.max_ns(), static_cast<double>(samples.back()));
  h.reset();
  EXPECT_EQ(h.count(), 0);
  EXPECT_EQ(h.quantile_ns(0.5), 0.0);
}

// below 256 ns the buckets are exact, so the rank is seen whole: the same nearest rank as
// realtime::percentile (the median of 1..10 is 5, its 0.95 quantile 10)
TEST(LatencyHistogram, RanksAsThePercentileDoes) {
  realtime::LatencyHistogram h;
  std::vector<int64_t> samples;
  for (int64_t v = 10; v >= 1; --v) {
    h.record(v);
    samples.push_back(v);
  }
  for (double q : {0.0, 0.1, 0.5, 0.55, 0.9, 0.95, 1.0})
    EXPECT_EQ(h.quantile_ns(q), static_cast<double>(percentile(samples, q))) << "q=" << q;
  EXPECT_EQ(h.quantile_ns(0.5), 5.0);
  EXPECT_EQ(h.quantile_ns(0.95), 10.0);
}

}  // namespace
}  // namespace pcisim::realtime
