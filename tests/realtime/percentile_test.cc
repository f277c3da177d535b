// The one percentile: nearest rank, by its definition on samples whose ranks are known.
#include "realtime/percentile.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace pcisim::realtime {
namespace {

TEST(Percentile, IsTheNearestRankOfTheSortedSamples) {
  // 1..100 shuffled: the q-quantile by nearest rank is ceil(100 q)
  std::vector<double> v;
  for (int i = 0; i < 100; ++i) v.push_back(double((i * 37) % 100 + 1));
  EXPECT_EQ(percentile(v, 0.5), 50.0);
  EXPECT_EQ(percentile(v, 0.95), 95.0);
  EXPECT_EQ(percentile(v, 0.99), 99.0);
  EXPECT_EQ(percentile(v, 0.951), 96.0) << "a rank between samples rounds up";
  EXPECT_EQ(percentile(v, 1.0), 100.0);
  EXPECT_EQ(percentile(v, 0.0), 1.0);
  EXPECT_EQ(percentile(v, -1.0), 1.0);
  EXPECT_EQ(percentile(v, 2.0), 100.0);
  EXPECT_EQ(percentile(v, std::nan("")), 1.0) << "a NaN q is taken as 0";
  EXPECT_EQ(v[0], 1.0) << "the caller's samples keep their order";
  EXPECT_EQ(v[1], 38.0);
}

TEST(Percentile, MedianOfAnEvenCountIsTheLowerMiddleAndOneSampleIsItself) {
  EXPECT_EQ(percentile(std::vector<double>{4, 1, 3, 2}, 0.5), 2.0);
  EXPECT_EQ(percentile(std::vector<double>{4, 1, 3}, 0.5), 3.0);
  EXPECT_EQ(percentile(std::vector<float>{7.5f}, 0.01), 7.5f);
  EXPECT_TRUE(std::isnan(percentile(std::vector<double>{}, 0.5))) << "no samples, no percentile";
}

TEST(Percentile, InPlaceReordersOnlyAndAgreesWithTheCopy) {
  std::vector<float> v{5, 9, 1, 7, 3, 8, 2, 6, 4, 10};
  const float copy = percentile(v, 0.9);
  EXPECT_EQ(percentile_in_place(std::span<float>(v), 0.9), copy);
  EXPECT_EQ(copy, 9.0f);
}

}  // namespace
}  // namespace pcisim::realtime
