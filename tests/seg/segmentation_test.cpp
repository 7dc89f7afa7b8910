#include "seg/segmentation.h"

#include <gtest/gtest.h>

namespace segslam::seg {
namespace {

InstanceMask Square(std::uint16_t id, float score, cv::Rect box) {
  InstanceMask instance;
  instance.track_id = id;
  instance.category_id = 1;
  instance.score = score;
  instance.mask = cv::Mat::zeros(20, 30, CV_8U);
  instance.mask(box).setTo(1);
  return instance;
}

TEST(FrameSegmentation, IdImagePaintsHigherScoresOnTop) {
  FrameSegmentation segmentation;
  segmentation.instances.push_back(Square(5, 0.9f, {0, 0, 10, 10}));
  segmentation.instances.push_back(Square(7, 0.4f, {5, 5, 10, 10}));
  const cv::Mat ids = segmentation.ToIdImage({30, 20});
  ASSERT_EQ(ids.type(), CV_16U);
  EXPECT_EQ(ids.at<std::uint16_t>(2, 2), 5);
  EXPECT_EQ(ids.at<std::uint16_t>(7, 7), 5);   // overlap: the 0.9 instance wins
  EXPECT_EQ(ids.at<std::uint16_t>(12, 12), 7);
  EXPECT_EQ(ids.at<std::uint16_t>(19, 29), 0);
  EXPECT_EQ(cv::countNonZero(ids == 7), 100 - 25);
}

TEST(FrameSegmentation, BoundsFitTheMasksPixels) {
  InstanceMask instance = Square(3, 1.0f, {4, 2, 5, 3});
  instance.mask.at<std::uint8_t>(15, 20) = 1;  // a second, detached part
  EXPECT_EQ(SearchBox(instance), cv::Rect(0, 0, 30, 20));  // not known: the whole frame
  FitBounds(&instance);
  EXPECT_EQ(instance.bounds, cv::Rect(4, 2, 17, 14));
  EXPECT_EQ(SearchBox(instance), instance.bounds);
  EXPECT_TRUE(BoundsHoldMask(instance));

  InstanceMask empty = Square(4, 1.0f, {0, 0, 0, 0});
  FitBounds(&empty);
  EXPECT_TRUE(empty.bounds.empty());
  EXPECT_TRUE(BoundsHoldMask(empty));
}

TEST(FrameSegmentation, BoundsNeedNotBeTightButMustHoldEveryPixel) {
  InstanceMask instance = Square(3, 1.0f, {4, 2, 5, 3});
  instance.bounds = cv::Rect(-10, 0, 25, 40);  // loose, past the frame: clipped to it
  EXPECT_EQ(SearchBox(instance), cv::Rect(0, 0, 15, 20));
  EXPECT_TRUE(BoundsHoldMask(instance));
  instance.bounds = cv::Rect(5, 2, 4, 3);  // leaves out column 4
  EXPECT_FALSE(BoundsHoldMask(instance));
}

// The id image reads each mask inside its bounds only: the same image as without them,
// and a pixel a wrong box leaves out is not painted.
TEST(FrameSegmentation, IdImageLooksOnlyInsideTheBounds) {
  FrameSegmentation segmentation;
  segmentation.instances.push_back(Square(5, 0.9f, {0, 0, 10, 10}));
  segmentation.instances.push_back(Square(7, 0.4f, {5, 5, 10, 10}));
  const cv::Mat unbounded = segmentation.ToIdImage({30, 20});
  for (InstanceMask& instance : segmentation.instances) FitBounds(&instance);
  EXPECT_EQ(cv::norm(segmentation.ToIdImage({30, 20}), unbounded, cv::NORM_INF), 0.0);

  segmentation.instances[1].bounds = cv::Rect(5, 5, 9, 10);
  const cv::Mat ids = segmentation.ToIdImage({30, 20});
  EXPECT_EQ(ids.at<std::uint16_t>(12, 14), 0);
  EXPECT_EQ(ids.at<std::uint16_t>(12, 13), 7);
}

}  // namespace
}  // namespace segslam::seg
