// The one percentile: nearest rank, by its definition on samples whose ranks are known; and the
// upper median the models' estimators take, the same selection at its stated rank.
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

// the models' estimators: the middle of an odd count (the 0.5 percentile), the upper of the two
// middle samples of an even count (the 0.5 percentile is the lower one), on shuffled samples
TEST(Percentile, UpperMedianIsTheMiddleOrTheUpperMiddle) {
  std::vector<double> odd{7, 1, 5, 3, 9};
  EXPECT_EQ(upper_median_in_place(std::span<double>(odd)), 5.0);
  EXPECT_EQ(percentile(std::vector<double>{7, 1, 5, 3, 9}, 0.5), 5.0);
  std::vector<double> even{8, 2, 6, 4};
  EXPECT_EQ(upper_median_in_place(std::span<double>(even)), 6.0);
  EXPECT_EQ(percentile(std::vector<double>{8, 2, 6, 4}, 0.5), 4.0);
  std::vector<double> rays(32);
  for (int i = 0; i < 32; ++i) rays[i] = (i * 13) % 32;  // 0..31 shuffled
  EXPECT_EQ(upper_median_in_place(std::span<double>(rays)), 16.0);
  std::vector<double> none;
  EXPECT_TRUE(std::isnan(upper_median_in_place(std::span<double>(none))));
}

}  // namespace
}  // namespace pcisim::realtime
