#include "core/statistics.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

namespace segslam {
namespace {

TEST(Median, MiddleValueOrMeanOfTheTwoMiddleValuesAsNumpy) {
  EXPECT_DOUBLE_EQ(Median({3, 1, 2}), 2);
  EXPECT_DOUBLE_EQ(Median({4, 1, 3, 2}), 2.5);
  EXPECT_DOUBLE_EQ(Median({-1, std::numeric_limits<double>::infinity(), 5}), 5);
  EXPECT_TRUE(std::isnan(Median({})));
}

TEST(Median, RefusesNaNInsteadOfSortingIt) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(Median({1, nan, 2}), std::invalid_argument);
  EXPECT_THROW(Median({nan}), std::invalid_argument);
}

}  // namespace
}  // namespace segslam
