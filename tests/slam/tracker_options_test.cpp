#include "slam/tracker_options.h"

#include <algorithm>
#include <string>

#include <gtest/gtest.h>

#include "core/error.h"

namespace segslam::slam {
namespace {

// SetTrackerOption's error, or "no error".
std::string SetMessage(TrackerOptions* options, const std::string& assignment) {
  try {
    SetTrackerOption(options, assignment);
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

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
  auto message = [&](const std::string& assignment) { return SetMessage(&options, assignment); };
  EXPECT_NE(message("last_frame_radius=15").find("unknown field 'last_frame_radius'"), std::string::npos);
  EXPECT_NE(message("last_frame_radius_px=fifteen").find("last_frame_radius_px: not a number"), std::string::npos);
  EXPECT_NE(message("min_tracking_inliers=30.5").find("min_tracking_inliers: not a whole number"), std::string::npos);
  EXPECT_NE(message("local_bundle_adjustment=2").find("expected 0 or 1"), std::string::npos);
  EXPECT_NE(message("last_frame_radius_px").find("expected NAME=VALUE"), std::string::npos);
  EXPECT_DOUBLE_EQ(options.last_frame_radius_px, TrackerOptions().last_frame_radius_px);
}

TEST(TrackerOptionOverridesTest, NamesAreSortedAndIncludeNestedFields) {
  const std::vector<std::string> names = TrackerOptionNames();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  for (const char* name : {"orb.levels", "motion_baseline_s", "pose_optimizer.rounds", "bundle_adjustment.chi2_stereo"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
  }
}

// Values outside an option's range are refused when set, naming the range and unit, and
// the tracker refuses a struct that holds one.
TEST(TrackerOptionOverridesTest, RangesAreCheckedWhenSetAndWhenATrackerIsMade) {
  TrackerOptions options;
  auto message = [&](const std::string& assignment) { return SetMessage(&options, assignment); };
  EXPECT_NE(message("min_rival_consensus=3").find("min_rival_consensus: 3 is outside its range >= 4"), std::string::npos);
  EXPECT_NE(message("depth_sigma_at_1m=0").find("depth_sigma_at_1m: 0 is outside its range > 0 m"), std::string::npos);
  EXPECT_NE(message("projection_ratio=1.5").find("projection_ratio: 1.5 is outside its range (0, 1]"), std::string::npos);
  EXPECT_NE(message("pose_optimizer.rounds=0").find("pose_optimizer.rounds: 0 is outside its range [1, 20]"),
            std::string::npos);
  EXPECT_EQ(message("pose_optimizer.rounds=2"), "no error");
  EXPECT_EQ(options.pose_optimizer.rounds, 2);

  TrackerOptions broken;
  broken.keyframe_tracked_ratio = 0;
  try {
    Tracker tracker(PinholeCamera::FromVerticalFov(64, 48, 50), broken);
    ADD_FAILURE() << "a tracker was made with keyframe_tracked_ratio 0";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("keyframe_tracked_ratio = 0 is outside its range (0, 1]"), std::string::npos)
        << e.what();
  }
}

// The effective options as results files echo them: every option once, typed, and the
// assignments that differ from the defaults.
TEST(TrackerOptionOverridesTest, EffectiveOptionsListEveryOptionWithItsType) {
  TrackerOptions options;
  SetTrackerOption(&options, "orb.max_features=1500");
  SetTrackerOption(&options, "projection_ratio=0.7");
  const auto& registry = TrackerOptionRegistry();
  const nlohmann::json json = registry.ToJson(options);
  EXPECT_EQ(json.size(), TrackerOptionNames().size());
  EXPECT_EQ(json.at("orb.max_features"), 1500);
  EXPECT_TRUE(json.at("orb.max_features").is_number_integer());
  EXPECT_EQ(json.at("local_bundle_adjustment"), true);
  EXPECT_DOUBLE_EQ(json.at("projection_ratio").get<double>(), 0.7) << "a float reads back as written";
  EXPECT_EQ(registry.Differences(options), (std::vector<std::string>{"orb.max_features=1500", "projection_ratio=0.7"}));
}

}  // namespace
}  // namespace segslam::slam
