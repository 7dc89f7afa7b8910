#include "seg/refiner_option_overrides.h"

#include <algorithm>
#include <string>

#include <gtest/gtest.h>

#include "core/error.h"

namespace segslam::seg {
namespace {

TEST(RefinerOptionOverridesTest, SetsRealIntegerBooleanAndRuleFields) {
  RefinerOptions options;
  SetRefinerOption(&options, "depth_tolerance=0.08");
  SetRefinerOption(&options, "hole_fill_iterations=4");
  SetRefinerOption(&options, "trim_keeps_region_depth=1");
  SetRefinerOption(&options, "require_same_category=0");
  SetRefinerOption(&options, "add_unmatched=1");
  EXPECT_DOUBLE_EQ(options.depth_tolerance, 0.08);
  EXPECT_EQ(options.hole_fill_iterations, 4);
  EXPECT_TRUE(options.trim_keeps_region_depth);
  EXPECT_FALSE(options.require_same_category);
  EXPECT_EQ(options.add_unmatched, AddUnmatchedRule::kPaperCountRule);
  // Untouched fields keep their defaults.
  EXPECT_DOUBLE_EQ(options.max_match_cost, RefinerOptions().max_match_cost);
  EXPECT_EQ(options.trim_instead_of_replace, RefinerOptions().trim_instead_of_replace);
}

TEST(RefinerOptionOverridesTest, RejectsUnknownNamesAndMalformedValuesNamingTheField) {
  RefinerOptions options;
  auto message = [&](const std::string& assignment) {
    try {
      SetRefinerOption(&options, assignment);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("depth_tol=0.1").find("unknown field 'depth_tol'"), std::string::npos);
  EXPECT_NE(message("depth_tolerance=wide").find("depth_tolerance: not a number"), std::string::npos);
  EXPECT_NE(message("hole_fill_iterations=1.5").find("hole_fill_iterations: not a whole number"), std::string::npos);
  EXPECT_NE(message("trim_keeps_region_depth=2").find("trim_keeps_region_depth: expected 0 or 1"), std::string::npos);
  EXPECT_NE(message("add_unmatched=3").find("add_unmatched: expected 0 (never)"), std::string::npos);
  EXPECT_NE(message("depth_tolerance").find("expected NAME=VALUE"), std::string::npos);
  EXPECT_DOUBLE_EQ(options.depth_tolerance, RefinerOptions().depth_tolerance);
  EXPECT_EQ(options.add_unmatched, RefinerOptions().add_unmatched);
}

// Every listed name is one SetRefinerOption takes (1 is a valid value of every kind).
TEST(RefinerOptionOverridesTest, NamesAreSortedAndEachIsSettable) {
  const std::vector<std::string> names = RefinerOptionNames();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  EXPECT_NE(std::find(names.begin(), names.end(), "trim_keeps_region_depth"), names.end());
  for (const std::string& name : names) {
    RefinerOptions options;
    EXPECT_NO_THROW(SetRefinerOption(&options, name + "=1")) << name;
  }
}

}  // namespace
}  // namespace segslam::seg
