// seg-eval's ground-truth object motion (seg/sequence_evaluation.h) on hand-made tracks;
// the whole evaluation on generated datasets is in seg_eval_test.cpp.
#include "seg/sequence_evaluation.h"

#include <gtest/gtest.h>

#include <optional>

namespace segslam::seg {
namespace {

Eigen::Isometry3d At(double x, double y) {
  return Eigen::Isometry3d(Eigen::Translation3d(x, y, 0));
}

TrackSample Sample(int frame, const Eigen::Isometry3d& T_world_object, bool moving) {
  TrackSample sample;
  sample.frame = frame;
  sample.stamp_s = frame / 30.0;
  sample.moving = moving;
  sample.T_world_object = T_world_object;
  return sample;
}

class RegionMotionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    gt_ids_ = cv::Mat(20, 20, CV_16U, cv::Scalar(0));
    gt_ids_(cv::Rect(5, 5, 6, 6)).setTo(7);
    InstanceMask region;
    region.track_id = 3;
    region.mask = cv::Mat(20, 20, CV_8U, cv::Scalar(0));
    region.mask(cv::Rect(4, 4, 6, 6)).setTo(1);
    previous_.instances.push_back(region);
    track_.instance_id = 7;
    index_[7] = &track_;
  }
  // The motion of region 3 into `frame` with the camera still at the origin.
  std::optional<Eigen::Vector3d> Shift(int frame) const {
    const auto motions = GroundTruthRegionMotions(previous_, gt_ids_, index_, frame, Eigen::Isometry3d::Identity(),
                                                  Eigen::Isometry3d::Identity());
    const auto it = motions.find(3);
    if (it == motions.end()) return std::nullopt;
    return it->second.translation();
  }

  cv::Mat gt_ids_;
  FrameSegmentation previous_;
  ObjectTrack track_;
  TrackIndex index_;
};

// An object still over frames 0 and 1 starts to move at frame 2 (tracks.json marks frame
// 2 moving: moved since frame 1). The motion into frame 2 is its first step.
TEST_F(RegionMotionTest, TheFirstStepOfAMotionIsTheObjects) {
  track_.samples = {Sample(0, At(1, 0), false), Sample(1, At(1, 0), false), Sample(2, At(1.2, 0), true)};
  ASSERT_TRUE(Shift(1).has_value());
  EXPECT_LT(Shift(1)->norm(), 1e-12);
  ASSERT_TRUE(Shift(2).has_value());
  EXPECT_NEAR((*Shift(2) - Eigen::Vector3d(0.2, 0, 0)).norm(), 0, 1e-12);
}

// Tracks may skip frames: samples are found by frame, not by position.
TEST_F(RegionMotionTest, SparseTracksAreReadByFrame) {
  track_.samples = {Sample(0, At(1, 0), false), Sample(4, At(2, 0), true), Sample(5, At(2.5, 0), true)};
  ASSERT_TRUE(Shift(5).has_value());
  EXPECT_NEAR((*Shift(5) - Eigen::Vector3d(0.5, 0, 0)).norm(), 0, 1e-12);
  EXPECT_FALSE(Shift(1).has_value());  // frame 1 has no sample
  EXPECT_FALSE(Shift(4).has_value());  // nor frame 3
}

}  // namespace
}  // namespace segslam::seg
