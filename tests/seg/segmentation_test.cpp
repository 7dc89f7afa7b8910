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

}  // namespace
}  // namespace segslam::seg
