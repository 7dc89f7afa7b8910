#include "core/statistics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

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

// What std::nth_element puts at index k: the independent answer.
float NthElement(std::vector<float> values, std::size_t k) {
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

TEST(KthSmallest, EqualsNthElementOnEveryKindOfSpread) {
  std::mt19937 rng(20261206);
  std::uniform_real_distribution<float> metres(0.1f, 40.0f);
  std::normal_distribution<float> surface(2.3f, 0.05f);
  std::uniform_real_distribution<float> exponent(-30.0f, 30.0f);
  struct Case {
    std::string name;
    std::vector<float> values;
  };
  std::vector<Case> cases;
  for (std::size_t n : {1, 2, 7, 2047, 2048, 5000, 60001}) {
    Case spread{"metres, n = " + std::to_string(n), {}};
    Case clustered{"one surface, n = " + std::to_string(n), {}};
    Case duplicates{"few distinct values, n = " + std::to_string(n), {}};
    Case wide{"1e-30 to 1e30, n = " + std::to_string(n), {}};
    for (std::size_t i = 0; i < n; ++i) {
      spread.values.push_back(metres(rng));
      clustered.values.push_back(std::max(0.01f, surface(rng)));
      duplicates.values.push_back(1.5f + 0.25f * static_cast<float>(rng() % 3));
      wide.values.push_back(std::pow(10.0f, exponent(rng)));
    }
    for (Case* c : {&spread, &clustered, &duplicates, &wide}) cases.push_back(std::move(*c));
  }
  cases.push_back({"all equal", std::vector<float>(5000, 3.25f)});
  // Outside (0, inf): selected by nth_element itself, still the same answer.
  std::vector<float> signed_values;
  for (int i = 0; i < 5000; ++i) signed_values.push_back(metres(rng) - 20.0f);
  signed_values.push_back(0.0f);
  cases.push_back({"negative and zero", signed_values});
  std::vector<float> with_infinity(4000, 1.0f);
  for (std::size_t i = 0; i < with_infinity.size(); ++i) with_infinity[i] = metres(rng);
  with_infinity[17] = std::numeric_limits<float>::infinity();
  cases.push_back({"an infinity", with_infinity});

  for (const Case& c : cases) {
    const std::size_t n = c.values.size();
    for (std::size_t k : {std::size_t{0}, n / 4, n / 2, n - 1}) {
      std::vector<float> scratch = c.values;
      EXPECT_EQ(KthSmallest(&scratch, k), NthElement(c.values, k)) << c.name << ", k = " << k;
    }
  }
}

TEST(KthSmallest, OverACountLooksOnlyAtThoseValues) {
  // The first 3000 values lie in [1, 2), the rest far below: a selection that read past
  // the count would find one of those.
  std::mt19937 rng(6122026);
  std::uniform_real_distribution<float> low(0.001f, 0.01f), counted(1.0f, 2.0f);
  std::vector<float> buffer(5000);
  for (std::size_t i = 0; i < buffer.size(); ++i) buffer[i] = i < 3000 ? counted(rng) : low(rng);
  const std::vector<float> first(buffer.begin(), buffer.begin() + 3000);
  for (std::size_t k : {std::size_t{0}, std::size_t{1500}, std::size_t{2999}}) {
    std::vector<float> scratch = buffer;
    EXPECT_EQ(KthSmallest(scratch.data(), 3000, k), NthElement(first, k)) << "k = " << k;
  }
  EXPECT_THROW(KthSmallest(buffer.data(), 3000, 3000), std::invalid_argument);
}

TEST(KthSmallest, RefusesARankBeyondTheValues) {
  std::vector<float> values = {1.0f, 2.0f};
  EXPECT_THROW(KthSmallest(&values, 2), std::invalid_argument);
  std::vector<float> none;
  EXPECT_THROW(KthSmallest(&none, 0), std::invalid_argument);
}

}  // namespace
}  // namespace segslam
