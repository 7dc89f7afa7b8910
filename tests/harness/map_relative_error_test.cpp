// The map-relative relocalization error (harness/map_relative_error.h) on hand-made
// trajectories: pass 2 is built from pass 1's estimate at a known place composed with a
// known error, so the expected figures are that error's.
#include "harness/map_relative_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/error.h"

namespace segslam::harness {
namespace {

constexpr double kRadiansPerDegree = 3.14159265358979323846 / 180.0;
constexpr int kFrames = 20;
constexpr double kStepM = 0.5;  // between frames along the route (x)

Eigen::Isometry3d Pose(double angle_rad, const Eigen::Vector3d& axis, const Eigen::Vector3d& translation) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
  T.translation() = translation;
  return T;
}

// A route along x with a slow turn; pass 2 drives it `lateral_m` beside (y) and
// `along_m` further on, so that its frame k's nearest pass-1 frame is frame k.
std::vector<StampedPose> Route(double first_stamp_s, double lateral_m, double along_m = 0, int frames = kFrames) {
  std::vector<StampedPose> route;
  for (int k = 0; k < frames; ++k) {
    route.push_back({first_stamp_s + 0.1 * k,
                     Pose(0.01 * k, Eigen::Vector3d::UnitZ(), Eigen::Vector3d(kStepM * k + along_m, lateral_m, 1.5))});
  }
  return route;
}

std::vector<double> Stamps(const std::vector<StampedPose>& poses) {
  std::vector<double> stamps;
  for (const StampedPose& pose : poses) stamps.push_back(pose.stamp_s);
  return stamps;
}

// Pass 1's estimate: the ground truth in a map frame off by `T_map_true`, with a
// different small error per frame (camera side) so that using another pass-1 frame than
// the intended place shows.
std::vector<StampedPose> PassOneEstimate(const std::vector<StampedPose>& ground_truth,
                                         const Eigen::Isometry3d& T_map_true) {
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0, 1);
  std::vector<StampedPose> estimate;
  for (const StampedPose& truth : ground_truth) {
    const Eigen::Vector3d axis(noise(random), noise(random), noise(random));
    const Eigen::Vector3d shift_m = 0.05 * Eigen::Vector3d(noise(random), noise(random), noise(random));
    estimate.push_back({truth.stamp_s, T_map_true * truth.T_wc * Pose(0.5 * kRadiansPerDegree, axis, shift_m)});
  }
  return estimate;
}

// Pass 2's estimate at frame i when consistent with pass 1's estimate at place j, then
// off by `T_error` (camera side): T̂2_i = T̂1_j (T1_j^-1 T2_i) T_error.
StampedPose ConsistentEstimate(const StampedPose& pass1_truth_j, const StampedPose& pass1_estimate_j,
                               const StampedPose& pass2_truth_i, const Eigen::Isometry3d& T_error) {
  return {pass2_truth_i.stamp_s,
          pass1_estimate_j.T_wc * pass1_truth_j.T_wc.inverse() * pass2_truth_i.T_wc * T_error};
}

Eigen::Isometry3d MapFrameError() {
  return Pose(5 * kRadiansPerDegree, Eigen::Vector3d(0.2, 0.1, 1), Eigen::Vector3d(0.8, -0.4, 0.2));
}

TEST(MapRelativeErrorTest, AKnownRigidErrorGivesItsNormAndAngle) {
  const std::vector<StampedPose> truth1 = Route(100, 0);
  const std::vector<StampedPose> estimate1 = PassOneEstimate(truth1, MapFrameError());
  const std::vector<StampedPose> truth2 = Route(500, 0.3, 0.1);
  // 0.03 m and 0.6 degrees: within both bounds.
  const Eigen::Isometry3d T_error = Pose(0.6 * kRadiansPerDegree, Eigen::Vector3d(1, -2, 0.5), Eigen::Vector3d(0.01, 0.02, -0.02));
  std::vector<StampedPose> estimate2;
  for (int i = 0; i < kFrames; ++i) estimate2.push_back(ConsistentEstimate(truth1[i], estimate1[i], truth2[i], T_error));

  const MapRelativeResult result = ComputeMapRelativeError(truth1, estimate1, Stamps(truth2), truth2, estimate2);
  ASSERT_EQ(result.frames.size(), static_cast<std::size_t>(kFrames));
  for (int i = 0; i < kFrames; ++i) EXPECT_EQ(result.frames[i].place_index, static_cast<std::size_t>(i));
  ASSERT_TRUE(result.translation_m.has_value());
  ASSERT_TRUE(result.rotation_deg.has_value());
  EXPECT_NEAR(result.translation_m->rmse, 0.03, 1e-9);
  EXPECT_NEAR(result.translation_m->max, 0.03, 1e-9);
  EXPECT_NEAR(result.rotation_deg->rmse, 0.6, 1e-9);
  EXPECT_EQ(result.frames_with_place, kFrames);
  EXPECT_EQ(result.frames_within, kFrames);
  EXPECT_DOUBLE_EQ(result.WithinShare(), 1.0);
}

TEST(MapRelativeErrorTest, AKnownRotationErrorGivesItsDegrees) {
  const std::vector<StampedPose> truth1 = Route(100, 0);
  const std::vector<StampedPose> estimate1 = PassOneEstimate(truth1, MapFrameError());
  const std::vector<StampedPose> truth2 = Route(500, -0.2);
  const Eigen::Isometry3d T_error = Pose(2.5 * kRadiansPerDegree, Eigen::Vector3d(0, 1, 0), Eigen::Vector3d::Zero());
  std::vector<StampedPose> estimate2;
  for (int i = 0; i < kFrames; ++i) estimate2.push_back(ConsistentEstimate(truth1[i], estimate1[i], truth2[i], T_error));

  const MapRelativeResult result = ComputeMapRelativeError(truth1, estimate1, Stamps(truth2), truth2, estimate2);
  ASSERT_TRUE(result.rotation_deg.has_value());
  EXPECT_NEAR(result.rotation_deg->rmse, 2.5, 1e-9);
  EXPECT_NEAR(result.rotation_deg->min, 2.5, 1e-9);
  EXPECT_NEAR(result.translation_m->rmse, 0, 1e-9);
  // 2.5 degrees is over the 1 degree bound, though the translation is exact.
  EXPECT_EQ(result.frames_within, 0);
  EXPECT_DOUBLE_EQ(result.WithinShare(), 0.0);
}

// Per frame a different error: 4 within, 2 too far, 2 turned too much, 2 without a pose.
TEST(MapRelativeErrorTest, TheWithinShareCountsFramesExactly) {
  const int frames = 10;
  const std::vector<StampedPose> truth1 = Route(100, 0, 0, frames);
  const std::vector<StampedPose> estimate1 = PassOneEstimate(truth1, MapFrameError());
  const std::vector<StampedPose> truth2 = Route(500, 0.3, 0, frames);
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), z = Eigen::Vector3d::UnitZ();
  const Eigen::Isometry3d T_errors[] = {
      Pose(0, z, 0.05 * x), Pose(0, z, 0.09 * x), Pose(0.9 * kRadiansPerDegree, z, Eigen::Vector3d::Zero()),
      Pose(0, z, Eigen::Vector3d::Zero()),                                           // within (4)
      Pose(0, z, 0.15 * x), Pose(0.5 * kRadiansPerDegree, z, 0.2 * x),               // too far (2)
      Pose(1.5 * kRadiansPerDegree, z, Eigen::Vector3d::Zero()), Pose(3 * kRadiansPerDegree, z, 0.01 * x),  // turned (2)
  };
  std::vector<StampedPose> estimate2;
  for (int i = 0; i < 8; ++i) estimate2.push_back(ConsistentEstimate(truth1[i], estimate1[i], truth2[i], T_errors[i]));
  // Frames 8 and 9 were processed but not estimated.

  const MapRelativeResult result = ComputeMapRelativeError(truth1, estimate1, Stamps(truth2), truth2, estimate2);
  EXPECT_EQ(result.frames_with_place, 10);
  EXPECT_EQ(result.frames_unestimated, 2);
  EXPECT_EQ(result.frames_within, 4);
  EXPECT_DOUBLE_EQ(result.WithinShare(), 0.4);
  // The RMSE is over the 8 estimated frames only.
  ASSERT_TRUE(result.translation_m.has_value());
  EXPECT_EQ(result.translation_m->count, 8u);
  const double squares_m2 = 0.05 * 0.05 + 0.09 * 0.09 + 0.15 * 0.15 + 0.2 * 0.2 + 0.01 * 0.01;
  EXPECT_NEAR(result.translation_m->rmse, std::sqrt(squares_m2 / 8), 1e-9);
  const double squares_deg2 = 0.9 * 0.9 + 0.5 * 0.5 + 1.5 * 1.5 + 3 * 3;
  EXPECT_NEAR(result.rotation_deg->rmse, std::sqrt(squares_deg2 / 8), 1e-9);
  EXPECT_FALSE(result.frames[8].has_estimate);
  EXPECT_FALSE(result.frames[8].within);
}

// The whole point: pass 1's map is off by a rigid transform and pass 2 relocalized
// perfectly on it. The ATE in the map's frame counts the map's error; this does not.
TEST(MapRelativeErrorTest, ACommonMapFrameErrorCancels) {
  const std::vector<StampedPose> truth1 = Route(100, 0);
  const std::vector<StampedPose> truth2 = Route(500, 0.4, 0.2);
  std::vector<StampedPose> estimate1 = truth1, estimate2 = truth2;
  for (StampedPose& pose : estimate1) pose.T_wc = MapFrameError() * pose.T_wc;
  for (StampedPose& pose : estimate2) pose.T_wc = MapFrameError() * pose.T_wc;

  const MapRelativeResult result = ComputeMapRelativeError(truth1, estimate1, Stamps(truth2), truth2, estimate2);
  ASSERT_TRUE(result.translation_m.has_value());
  EXPECT_LT(result.translation_m->max, 1e-9);
  EXPECT_LT(result.rotation_deg->max, 1e-6);
  EXPECT_DOUBLE_EQ(result.WithinShare(), 1.0);

  AteOptions in_map_frame;
  in_map_frame.align = false;
  EXPECT_GT(ComputeAte(truth2, estimate2, in_map_frame).translation_m.rmse, 0.3);
}

// A pass-1 frame without an estimate is no place: pass-2 frame 5, nearest to pass-1
// frame 5 (lost), is scored against pass-1 frame 6, the nearest estimated one.
TEST(MapRelativeErrorTest, PassOneFramesWithoutAnEstimateAreNoPlace) {
  const std::vector<StampedPose> truth1 = Route(100, 0);
  std::vector<StampedPose> estimate1 = PassOneEstimate(truth1, MapFrameError());
  estimate1.erase(estimate1.begin() + 5);  // estimate1[5] is now frame 6's
  const std::vector<StampedPose> truth2 = Route(500, 0.1, 0.05);  // frame 5 is nearer 6 than 4
  std::vector<StampedPose> estimate2;
  for (int i = 0; i < kFrames; ++i) {
    const int j = i < 5 ? i : (i == 5 ? 6 : i);
    const int estimate_index = j < 5 ? j : j - 1;
    estimate2.push_back(ConsistentEstimate(truth1[j], estimate1[estimate_index], truth2[i], Eigen::Isometry3d::Identity()));
  }

  const MapRelativeResult result = ComputeMapRelativeError(truth1, estimate1, Stamps(truth2), truth2, estimate2);
  EXPECT_EQ(result.frames[5].place_index, 5u);  // estimate1's index of frame 6
  EXPECT_NEAR(result.frames[5].place_distance_m, std::hypot(kStepM - 0.05, 0.1), 1e-9);
  ASSERT_TRUE(result.translation_m.has_value());
  EXPECT_LT(result.translation_m->max, 1e-9);
  EXPECT_EQ(result.frames_within, kFrames);
}

// Pass 2 drives 5 m past pass 1's last frame: frames further than max_place_distance_m
// from every pass-1 place are excluded and counted, not scored.
TEST(MapRelativeErrorTest, FramesFarFromEveryPlaceAreExcludedAndCounted) {
  const std::vector<StampedPose> truth1 = Route(100, 0);
  const std::vector<StampedPose> estimate1 = PassOneEstimate(truth1, MapFrameError());
  const std::vector<StampedPose> truth2 = Route(500, 0, 0, kFrames + 10);  // to x = 14.5 m; pass 1 ends at 9.5 m
  std::vector<StampedPose> estimate2;
  for (int i = 0; i < kFrames + 10; ++i) {
    const int j = std::min(i, kFrames - 1);
    estimate2.push_back(ConsistentEstimate(truth1[j], estimate1[j], truth2[i], Eigen::Isometry3d::Identity()));
  }

  MapRelativeOptions options;
  options.max_place_distance_m = 1.2;  // frames kFrames and kFrames + 1 (0.5, 1.0 m) keep a place
  const MapRelativeResult result = ComputeMapRelativeError(truth1, estimate1, Stamps(truth2), truth2, estimate2, options);
  EXPECT_EQ(result.frames_with_place, kFrames + 2);
  EXPECT_EQ(result.frames_without_place, 8);
  EXPECT_FALSE(result.frames[kFrames + 2].has_place);
  EXPECT_EQ(result.frames_within, kFrames + 2);
  EXPECT_DOUBLE_EQ(result.WithinShare(), 1.0);
  EXPECT_EQ(result.translation_m->count, static_cast<std::size_t>(kFrames + 2));

  // No pass-1 estimate at all: nothing has a place, nothing is scored.
  const MapRelativeResult no_map = ComputeMapRelativeError(truth1, {}, Stamps(truth2), truth2, estimate2);
  EXPECT_EQ(no_map.frames_without_place, kFrames + 10);
  EXPECT_FALSE(no_map.translation_m.has_value());
  EXPECT_TRUE(std::isnan(no_map.WithinShare()));
}

TEST(MapRelativeErrorTest, InvalidOptionsAreRefused) {
  MapRelativeOptions options;
  EXPECT_EQ(options.Check(), "");
  options.max_place_distance_m = 0;
  EXPECT_NE(options.Check().find("max_place_distance_m"), std::string::npos);
  EXPECT_THROW(ComputeMapRelativeError({}, {}, {}, {}, {}, options), Error);
}

}  // namespace
}  // namespace segslam::harness
