#include "slam/tracker_option_overrides.h"

#include <algorithm>
#include <string>

#include <gtest/gtest.h>

#include "core/error.h"

namespace segslam::slam {
namespace {

TEST(TrackerOptionOverridesTest, SetsRealIntegerBooleanAndNestedFields) {
  TrackerOptions options;
  SetTrackerOption(&options, "last_frame_radius_px=15");
  SetTrackerOption(&options, "min_tracking_inliers=40");
  SetTrackerOption(&options, "local_bundle_adjustment=0");
  SetTrackerOption(&options, "orb.max_features=1500");
  SetTrackerOption(&options, "moving_distance_per_m=0.025");
  SetTrackerOption(&options, "orb.max_depth_m=60");
  EXPECT_DOUBLE_EQ(options.last_frame_radius_px, 15);
  EXPECT_EQ(options.min_tracking_inliers, 40);
  EXPECT_FALSE(options.local_bundle_adjustment);
  EXPECT_EQ(options.orb.max_features, 1500);
  EXPECT_DOUBLE_EQ(options.moving_distance_per_m, 0.025);
  EXPECT_FLOAT_EQ(options.orb.max_depth_m, 60.0f);
  // Untouched fields keep their defaults.
  EXPECT_DOUBLE_EQ(options.local_map_radius_px, TrackerOptions().local_map_radius_px);
}

TEST(TrackerOptionOverridesTest, RejectsUnknownNamesAndMalformedValuesNamingTheField) {
  TrackerOptions options;
  auto message = [&](const std::string& assignment) {
    try {
      SetTrackerOption(&options, assignment);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("last_frame_radius=15").find("unknown field 'last_frame_radius'"), std::string::npos);
  EXPECT_NE(message("last_frame_radius_px=fifteen").find("last_frame_radius_px: not a number"), std::string::npos);
  EXPECT_NE(message("min_tracking_inliers=30.5").find("min_tracking_inliers: not a whole number"), std::string::npos);
  EXPECT_NE(message("local_bundle_adjustment=2").find("expected 0 or 1"), std::string::npos);
  EXPECT_NE(message("last_frame_radius_px").find("expected NAME=VALUE"), std::string::npos);
  EXPECT_DOUBLE_EQ(options.last_frame_radius_px, TrackerOptions().last_frame_radius_px);
}

TEST(TrackerOptionOverridesTest, NamesAreSortedAndIncludeNestedOrbFields) {
  const std::vector<std::string> names = TrackerOptionNames();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  EXPECT_NE(std::find(names.begin(), names.end(), "orb.levels"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "motion_baseline_s"), names.end());
}

}  // namespace
}  // namespace segslam::slam
