#include "slam/orb_extractor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace segslam::slam {
namespace {

PinholeCamera CameraFor(int width, int height) {
  PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = 525;
  camera.cx = 0.5 * (width - 1);
  camera.cy = 0.5 * (height - 1);
  return camera;
}

// Random overlapping rectangles and discs with grey levels drawn from [low, low + contrast]
// inside `area`: many corners of a known strength range everywhere in it.
void DrawShapes(cv::Mat* image, const cv::Rect& area, int count, int low, int contrast,
                cv::RNG* rng) {
  for (int i = 0; i < count; ++i) {
    const int x = area.x + rng->uniform(0, area.width);
    const int y = area.y + rng->uniform(0, area.height);
    const int size = rng->uniform(6, 40);
    const cv::Scalar grey(low + rng->uniform(0, contrast + 1));
    if (rng->uniform(0, 2) == 0) {
      cv::rectangle(*image, cv::Rect(x, y, size, rng->uniform(6, 40)) & area, grey, cv::FILLED);
    } else {
      cv::circle(*image, {x, y}, size / 2, grey, cv::FILLED, cv::LINE_AA);
    }
  }
}

cv::Mat TexturedImage(int width, int height, std::uint64_t seed) {
  cv::Mat image(height, width, CV_8U, cv::Scalar(128));
  cv::RNG rng(seed);
  DrawShapes(&image, cv::Rect(0, 0, width, height), 1500, 0, 255, &rng);
  return image;
}

TEST(OrbExtractorTest, LevelScalesAndBudgets) {
  const OrbExtractor extractor;
  ASSERT_EQ(extractor.scale_factors().size(), 8u);
  EXPECT_FLOAT_EQ(extractor.scale_factors()[0], 1.0f);
  EXPECT_NEAR(extractor.scale_factors()[7], std::pow(1.2, 7), 1e-5);
  EXPECT_NEAR(extractor.level_sigma2()[3], std::pow(1.2, 6), 1e-5);
  EXPECT_NEAR(extractor.inverse_level_sigma2()[3], std::pow(1.2, -6), 1e-7);
  const std::vector<int>& budgets = extractor.features_per_level();
  EXPECT_EQ(std::accumulate(budgets.begin(), budgets.end(), 0), 1000);
  // Geometric in 1/1.2: level 0 gets 1000 * (1 - 1/1.2) / (1 - 1.2^-8) = 217.
  EXPECT_EQ(budgets[0], 217);
  for (size_t l = 1; l + 1 < budgets.size(); ++l) {
    EXPECT_NEAR(budgets[l], budgets[0] / std::pow(1.2, l), 0.5 + 1e-9) << "level " << l;
  }
}

TEST(OrbExtractorTest, TexturedImageYieldsNearlyTheBudgetWithConsistentAttributes) {
  const PinholeCamera camera = CameraFor(640, 480);
  const OrbExtractor extractor;
  const FrameFeatures f = extractor.Extract(TexturedImage(640, 480, 1), cv::Mat(), camera);
  EXPECT_GE(f.size(), 950u);
  EXPECT_LE(f.size(), 1000u);
  ASSERT_EQ(f.descriptors.rows, static_cast<int>(f.size()));
  EXPECT_EQ(f.descriptors.cols, 32);
  EXPECT_EQ(f.descriptors.type(), CV_8U);
  ASSERT_EQ(f.depth_m.size(), f.size());
  ASSERT_EQ(f.points_cam.size(), f.size());
  std::vector<int> per_level(8, 0);
  for (size_t i = 0; i < f.size(); ++i) {
    const cv::KeyPoint& k = f.keypoints[i];
    ASSERT_GE(k.octave, 0);
    ASSERT_LT(k.octave, 8);
    ++per_level[k.octave];
    const float scale = extractor.scale_factors()[k.octave];
    // Border of 19 level pixels, mapped to level 0 with centre-aligned scaling.
    const float margin = (OrbExtractor::kBorderPx + 0.5f) * scale - 0.5f - 0.6f;
    EXPECT_GE(k.pt.x, margin);
    EXPECT_GE(k.pt.y, margin);
    EXPECT_LE(k.pt.x, 639 - margin);
    EXPECT_LE(k.pt.y, 479 - margin);
    EXPECT_NEAR(k.size, 31 * scale, 1e-3);
    EXPECT_GE(k.angle, 0);
    EXPECT_LT(k.angle, 360);
    EXPECT_GE(k.response, 7);
    EXPECT_FALSE(f.HasDepth(i));
  }
  for (int l = 0; l < 8; ++l) {
    EXPECT_LE(per_level[l], extractor.features_per_level()[l]) << "level " << l;
    EXPECT_GE(per_level[l], extractor.features_per_level()[l] * 9 / 10) << "level " << l;
  }
}

TEST(OrbExtractorTest, UniformTextureCoversEveryCellOfA4x4Grid) {
  const PinholeCamera camera = CameraFor(640, 480);
  const FrameFeatures f = OrbExtractor().Extract(TexturedImage(640, 480, 2), cv::Mat(), camera);
  int cells[4][4] = {};
  for (const cv::KeyPoint& k : f.keypoints) {
    ++cells[std::min(3, static_cast<int>(k.pt.y / 120))]
           [std::min(3, static_cast<int>(k.pt.x / 160))];
  }
  // 1000 features over 16 cells: 62 on average; border cells lose the unfeatured margin.
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) EXPECT_GE(cells[r][c], 25) << "cell row " << r << " col " << c;
  }
}

TEST(OrbExtractorTest, WeakTextureKeepsItsShareNextToStrongTexture) {
  // Left half: high-contrast shapes; right half: the same kind of shapes at contrast 40,
  // whose FAST scores are far below the left half's. Taking the strongest corners would
  // put nearly everything on the left; the spatial distribution must not.
  cv::Mat image(480, 640, CV_8U, cv::Scalar(128));
  cv::RNG rng(3);
  DrawShapes(&image, cv::Rect(0, 0, 320, 480), 800, 0, 255, &rng);
  DrawShapes(&image, cv::Rect(320, 0, 320, 480), 800, 108, 40, &rng);
  const FrameFeatures f = OrbExtractor().Extract(image, cv::Mat(), CameraFor(640, 480));
  ASSERT_GT(f.size(), 800u);
  const auto right = std::count_if(f.keypoints.begin(), f.keypoints.end(),
                                   [](const cv::KeyPoint& k) { return k.pt.x >= 330; });
  // The weak half has fewer corners above threshold, so it gets fewer leaves, but far
  // from none (strongest-first selection would leave it a few percent).
  EXPECT_GE(right, static_cast<long>(f.size() / 5));
}

TEST(OrbExtractorTest, LowContrastCornersAreFoundByTheCellRetryThreshold) {
  // Contrast 12 lies between the minimum (7) and initial (20) FAST thresholds.
  cv::Mat image(480, 640, CV_8U, cv::Scalar(100));
  cv::RNG rng(4);
  for (int y = 30; y < 450; y += 40) {
    for (int x = 30; x < 610; x += 40)
      cv::rectangle(image, cv::Rect(x, y, 14, 14), cv::Scalar(112), cv::FILLED);
  }
  const PinholeCamera camera = CameraFor(640, 480);
  const FrameFeatures with_retry = OrbExtractor().Extract(image, cv::Mat(), camera);
  EXPECT_GT(with_retry.size(), 100u);
  OrbExtractorOptions no_retry;
  no_retry.min_fast_threshold = no_retry.initial_fast_threshold;
  EXPECT_EQ(OrbExtractor(no_retry).Extract(image, cv::Mat(), camera).size(), 0u);
}

TEST(OrbExtractorTest, DepthIsReadAtTheRoundedPositionAndBackProjected) {
  const PinholeCamera camera = CameraFor(640, 480);
  // A slanted plane, with a missing band (0), a band beyond max depth and a NaN band.
  cv::Mat depth(480, 640, CV_32F);
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) depth.at<float>(y, x) = 2.0f + 0.004f * x + 0.002f * y;
  }
  depth.colRange(0, 160).setTo(0.0f);
  depth.colRange(160, 240).setTo(55.0f);
  depth.colRange(240, 300).setTo(std::numeric_limits<float>::quiet_NaN());
  const FrameFeatures f = OrbExtractor().Extract(TexturedImage(640, 480, 5), depth, camera);
  ASSERT_GT(f.size(), 900u);
  int with_depth = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    const cv::Point2f pt = f.keypoints[i].pt;
    const int x = cvRound(pt.x);
    const int y = cvRound(pt.y);
    if (x < 300) {
      EXPECT_FALSE(f.HasDepth(i)) << "x " << pt.x;
      EXPECT_EQ(f.points_cam[i], Eigen::Vector3d::Zero());
      continue;
    }
    ++with_depth;
    ASSERT_TRUE(f.HasDepth(i)) << "x " << pt.x;
    EXPECT_FLOAT_EQ(f.depth_m[i], 2.0f + 0.004f * x + 0.002f * y);
    const Eigen::Vector3d& p = f.points_cam[i];
    EXPECT_NEAR(p.z(), f.depth_m[i], 1e-6);
    const Eigen::Vector2d reprojected = camera.Project(p);
    EXPECT_NEAR(reprojected.x(), pt.x, 1e-4);
    EXPECT_NEAR(reprojected.y(), pt.y, 1e-4);
  }
  EXPECT_GT(with_depth, 400);
}

TEST(OrbExtractorTest, DescriptorsMatchAcrossA90DegreeRotation) {
  const cv::Mat image = TexturedImage(640, 480, 6);
  cv::Mat rotated;
  cv::rotate(image, rotated, cv::ROTATE_90_CLOCKWISE);  // (x, y) -> (479 - y, x)
  const OrbExtractor extractor;
  const FrameFeatures a = extractor.Extract(image, cv::Mat(), CameraFor(640, 480));
  const FrameFeatures b = extractor.Extract(rotated, cv::Mat(), CameraFor(480, 640));
  std::vector<cv::DMatch> matches;
  cv::BFMatcher(cv::NORM_HAMMING, /*crossCheck=*/true).match(a.descriptors, b.descriptors, matches);
  ASSERT_GT(matches.size(), 300u);
  int at_rotated_position = 0;
  std::vector<double> angle_errors;
  for (const cv::DMatch& m : matches) {
    const cv::KeyPoint& ka = a.keypoints[m.queryIdx];
    const cv::KeyPoint& kb = b.keypoints[m.trainIdx];
    const cv::Point2f expected(479.0f - ka.pt.y, ka.pt.x);
    if (cv::norm(expected - kb.pt) > 2.0 * extractor.scale_factors()[ka.octave]) continue;
    ++at_rotated_position;
    // A clockwise image rotation turns the direction atan2(dy, dx) by +90 degrees.
    double error = std::fmod(kb.angle - ka.angle - 90.0 + 720.0, 360.0);
    angle_errors.push_back(std::min(error, 360.0 - error));
  }
  EXPECT_GE(at_rotated_position, static_cast<int>(0.8 * matches.size()));
  ASSERT_FALSE(angle_errors.empty());
  std::nth_element(angle_errors.begin(), angle_errors.begin() + angle_errors.size() / 2,
                   angle_errors.end());
  EXPECT_LT(angle_errors[angle_errors.size() / 2], 3.0);
}

TEST(OrbExtractorTest, BlankImageGivesNoFeatures) {
  const cv::Mat blank(480, 640, CV_8U, cv::Scalar(90));
  const cv::Mat depth(480, 640, CV_32F, cv::Scalar(1.5f));
  const FrameFeatures f = OrbExtractor().Extract(blank, depth, CameraFor(640, 480));
  EXPECT_EQ(f.size(), 0u);
  EXPECT_EQ(f.descriptors.rows, 0);
  EXPECT_TRUE(f.depth_m.empty());
  EXPECT_TRUE(f.points_cam.empty());
}

TEST(OrbExtractorTest, SmallImageUsesOnlyTheLevelsThatFit) {
  // 80x60: level 0 leaves a 42x22 detection region; from 1.2^2 on nothing fits.
  const FrameFeatures f =
      OrbExtractor().Extract(TexturedImage(80, 60, 7), cv::Mat(), CameraFor(80, 60));
  for (const cv::KeyPoint& k : f.keypoints) EXPECT_LE(k.octave, 1);
  EXPECT_EQ(f.descriptors.rows, static_cast<int>(f.size()));
}

TEST(OrbExtractorTest, RejectsWrongInput) {
  const PinholeCamera camera = CameraFor(640, 480);
  const OrbExtractor extractor;
  const cv::Mat gray(480, 640, CV_8U, cv::Scalar(0));
  EXPECT_THROW(extractor.Extract(cv::Mat(), cv::Mat(), camera), Error);
  EXPECT_THROW(extractor.Extract(cv::Mat(480, 640, CV_8UC3), cv::Mat(), camera), Error);
  EXPECT_THROW(extractor.Extract(cv::Mat(480, 640, CV_16U), cv::Mat(), camera), Error);
  EXPECT_THROW(extractor.Extract(gray, cv::Mat(), CameraFor(320, 240)), Error);
  EXPECT_THROW(extractor.Extract(gray, cv::Mat(480, 640, CV_16U), camera), Error);
  EXPECT_THROW(extractor.Extract(gray, cv::Mat(240, 320, CV_32F), camera), Error);
  EXPECT_THROW(extractor.Extract(gray, cv::Mat(), PinholeCamera{}), Error);

  OrbExtractorOptions bad;
  bad.scale_factor = 1.0f;
  EXPECT_THROW(OrbExtractor{bad}, Error);
  bad = {};
  bad.min_fast_threshold = 30;
  EXPECT_THROW(OrbExtractor{bad}, Error);
  bad = {};
  bad.max_features = 0;
  EXPECT_THROW(OrbExtractor{bad}, Error);
  bad = {};
  bad.max_depth_m = 0.05f;
  EXPECT_THROW(OrbExtractor{bad}, Error);
}

}  // namespace
}  // namespace segslam::slam
