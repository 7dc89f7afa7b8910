#include "seg/refiner_options.h"

#include <algorithm>
#include <cmath>
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
  EXPECT_NE(message("add_unmatched=3").find("add_unmatched: 3 is outside its range [0, 2]"), std::string::npos);
  EXPECT_NE(message("depth_tolerance=1").find("depth_tolerance: 1 is outside its range [0, 1)"), std::string::npos);
  EXPECT_NE(message("min_depth_m=0").find("min_depth_m: 0 is outside its range > 0 m"), std::string::npos);
  EXPECT_NE(message("depth_tolerance").find("expected NAME=VALUE"), std::string::npos);
  EXPECT_DOUBLE_EQ(options.depth_tolerance, RefinerOptions().depth_tolerance);
  EXPECT_EQ(options.add_unmatched, RefinerOptions().add_unmatched);
}

// Every listed name is one SetRefinerOption takes, its default among its values, and
// each range's ends are where the options stop being valid (RefinerOptions::IsValid).
TEST(RefinerOptionOverridesTest, NamesAreSortedAndEachIsSettableToItsDefault) {
  const std::vector<std::string> names = RefinerOptionNames();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  EXPECT_NE(std::find(names.begin(), names.end(), "trim_keeps_region_depth"), names.end());
  const auto& registry = RefinerOptionRegistry();
  for (const auto& spec : registry.specs()) {
    RefinerOptions options;
    EXPECT_NO_THROW(SetRefinerOption(&options, spec.name + "=" + FormatOptionValue(spec.get(RefinerOptions()))))
        << spec.name;
    EXPECT_FALSE(spec.help.empty()) << spec.name;
  }
  EXPECT_EQ(registry.ToJson(RefinerOptions()).size(), names.size());
}

// The one check of a whole struct: in range and the weights not both 0.
TEST(RefinerOptionOverridesTest, IsValidChecksEveryRangeAndTheWeights) {
  std::string error;
  EXPECT_TRUE(RefinerOptions().IsValid(&error)) << error;
  RefinerOptions options;
  options.occlusion_tolerance = 1.0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("occlusion_tolerance = 1 is outside its range [0, 1)"), std::string::npos) << error;
  options = RefinerOptions();
  options.w_barycenter = 0;
  options.w_shape = 0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("must not both be 0"), std::string::npos) << error;
  options = RefinerOptions();
  options.max_match_cost = std::nan("");
  EXPECT_FALSE(options.IsValid(&error)) << "NaN lies in no range";
}

}  // namespace
}  // namespace segslam::seg
