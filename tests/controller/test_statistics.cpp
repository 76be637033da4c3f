// The one percentile definition of the summaries (controller/statistics.hpp): nearest rank, always
// one of the samples, and no value at all (not 0) without samples.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "controller/statistics.hpp"

namespace stride {
namespace test_statistics {

TEST(Statistics, PercentileIsTheNearestRank) {
  const std::vector<double> v = {5.0, 1.0, 4.0, 2.0, 3.0};  // not sorted: the function sorts
  EXPECT_EQ(percentile(v, 0.5), 3.0);                       // ceil(2.5) = 3rd
  EXPECT_EQ(percentile(v, 0.99), 5.0);                      // ceil(4.95) = 5th
  EXPECT_EQ(percentile(v, 1.0), 5.0);
  EXPECT_EQ(percentile(v, 0.0), 1.0);  // the smallest
  EXPECT_EQ(percentile(v, 0.2), 1.0);  // exactly 1 of 5 at or below: the 1st, not the 2nd
  EXPECT_EQ(percentile(v, 0.21), 2.0);
  EXPECT_EQ(percentile({7.0}, 0.5), 7.0);
}

TEST(Statistics, ARankThatIsAnIntegerIsNotRoundedUp) {
  // 1..100: the p-th percentile is p * 100 itself, also where p * n as doubles is a hair above an
  // integer (0.07 * 100 = 7.000000000000001).
  std::vector<double> v(100);
  std::iota(v.begin(), v.end(), 1.0);
  EXPECT_EQ(percentile(v, 0.5), 50.0);
  EXPECT_EQ(percentile(v, 0.99), 99.0);
  EXPECT_EQ(percentile(v, 0.07), 7.0);
  EXPECT_EQ(percentile(v, 1.0), 100.0);
}

TEST(Statistics, NoSamplesIsNoValue) {
  EXPECT_FALSE(percentile({}, 0.5).has_value());
  EXPECT_FALSE(percentile({}, 1.0).has_value());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(percentile({nan, nan}, 0.5).has_value());
  const Percentiles p = percentiles({});
  EXPECT_EQ(p.count, 0);
  EXPECT_FALSE(p.p50.has_value());
  EXPECT_FALSE(p.p99.has_value());
  EXPECT_FALSE(p.max.has_value());
}

TEST(Statistics, NaNSamplesAreLeftOut) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(percentile({nan, 2.0, nan, 1.0, 3.0}, 1.0), 3.0);
  EXPECT_EQ(percentiles({nan, 2.0, 1.0}).count, 2);
}

TEST(Statistics, PercentilesAgreeWithPercentile) {
  std::vector<double> v;
  for (int i = 0; i < 250; ++i) v.push_back(std::fmod(37.0 * i, 251.0));  // 250 distinct, shuffled
  const Percentiles p = percentiles(v);
  EXPECT_EQ(p.count, 250);
  EXPECT_EQ(p.p50, percentile(v, 0.5));
  EXPECT_EQ(p.p99, percentile(v, 0.99));
  EXPECT_EQ(p.max, percentile(v, 1.0));
  EXPECT_EQ(p.max, *std::max_element(v.begin(), v.end()));
}

}  // namespace test_statistics
}  // namespace stride
