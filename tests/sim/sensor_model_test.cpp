#include "sim/sensor_model.h"

#include <gtest/gtest.h>

#include <cmath>

namespace segslam::sim {
namespace {

const PinholeCamera kCamera = PinholeCamera::FromVerticalFov(160, 120, 60.0);

// Depth ramps from 1 m (left) to 8 m (right) in vertical bands; grey colour.
RenderedFrame Ramp() {
  RenderedFrame f;
  f.color_bgr = cv::Mat(120, 160, CV_8UC3, cv::Scalar(128, 128, 128));
  f.depth_m = cv::Mat(120, 160, CV_32F);
  for (int c = 0; c < 160; ++c) f.depth_m.col(c).setTo(1.0 + 7.0 * (c / 20) / 7.0);
  f.instance_ids = cv::Mat::zeros(120, 160, CV_16U);
  return f;
}

bool Identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

RenderedFrame Applied(const SensorModel& model, std::uint64_t seed, int pass, int frame) {
  RenderedFrame f = Ramp();
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  model.Apply(seed, pass, frame, I, I, &f);
  return f;
}

TEST(SensorModelTest, SameKeyGivesSameNoiseOtherFramesDiffer) {
  const SensorModel model(scenes::SensorSpec{}, kCamera, 10.0, /*fps=*/15.0);
  const RenderedFrame a = Applied(model, 42, 0, 3);
  const RenderedFrame b = Applied(model, 42, 0, 3);
  EXPECT_TRUE(Identical(a.depth_m, b.depth_m));
  EXPECT_TRUE(Identical(a.color_bgr, b.color_bgr));
  for (const RenderedFrame& other :
       {Applied(model, 42, 0, 4), Applied(model, 42, 1, 3), Applied(model, 43, 0, 3)}) {
    EXPECT_FALSE(Identical(a.depth_m, other.depth_m));
    EXPECT_FALSE(Identical(a.color_bgr, other.color_bgr));
  }
}

TEST(SensorModelTest, DisabledSensorLeavesTheFrameBitIdentical) {
  scenes::SensorSpec spec;
  spec.enabled = false;
  spec.motion_blur = true;
  const SensorModel model(spec, kCamera, 10.0, /*fps=*/15.0);
  const RenderedFrame clean = Ramp();
  const RenderedFrame out = Applied(model, 1, 0, 0);
  EXPECT_TRUE(Identical(clean.depth_m, out.depth_m));
  EXPECT_TRUE(Identical(clean.color_bgr, out.color_bgr));
}

TEST(SensorModelTest, DepthNoiseGrowsWithDepthSquared) {
  scenes::SensorSpec spec;
  spec.depth_quantization = 0;
  spec.edge_dropout = 0;
  spec.depth_noise_sigma_at_1m = 0.01;
  const SensorModel model(spec, kCamera, 10.0, /*fps=*/15.0);
  const RenderedFrame clean = Ramp();
  const RenderedFrame noisy = Applied(model, 7, 0, 0);
  auto sigma_of_band = [&](int band) {
    cv::Mat diff = noisy.depth_m.colRange(band * 20 + 2, band * 20 + 18) -
                   clean.depth_m.colRange(band * 20 + 2, band * 20 + 18);
    cv::Scalar mean, stddev;
    cv::meanStdDev(diff, mean, stddev);
    return stddev[0];
  };
  const double near_sigma = sigma_of_band(0);  // 1 m
  const double far_sigma = sigma_of_band(3);   // 4 m
  EXPECT_NEAR(near_sigma, 0.01, 0.002);
  EXPECT_NEAR(far_sigma / near_sigma, 16.0, 3.0);
}

TEST(SensorModelTest, QuantizesToDisparityStepsAndLimitsTheRange) {
  scenes::SensorSpec spec;
  spec.depth_noise_sigma_at_1m = 0;
  spec.edge_dropout = 0;
  spec.max_depth_m = 6.5;
  spec.min_depth_m = 1.5;
  const SensorModel model(spec, kCamera, 10.0, /*fps=*/15.0);
  const RenderedFrame out = Applied(model, 7, 0, 0);
  const double fb = kCamera.fx * SensorModel::kBaselineM;
  int valid = 0;
  for (int c = 0; c < 160; ++c) {
    const double truth = 1.0 + 7.0 * (c / 20) / 7.0;
    const float z = out.depth_m.at<float>(60, c);
    if (truth < 1.5 || truth > 6.5) {
      EXPECT_EQ(z, 0.0f) << "column " << c;
      continue;
    }
    ASSERT_GT(z, 0.0f) << "column " << c;
    ++valid;
    const double steps = fb / z / SensorModel::kDisparityStepPx;
    EXPECT_NEAR(steps, std::round(steps), 1e-3);
    // Quantization error is at most half a step.
    EXPECT_LE(std::abs(z - truth), 0.5 * SensorModel::kDisparityStepPx * truth * truth / fb +
                                       1e-4);
  }
  EXPECT_GT(valid, 0);
}

TEST(SensorModelTest, DropsDepthOnEdgesOnly) {
  scenes::SensorSpec spec;
  spec.depth_noise_sigma_at_1m = 0;
  spec.depth_quantization = 0;
  spec.edge_dropout = 1.0;
  const SensorModel model(spec, kCamera, 10.0, /*fps=*/15.0);
  const RenderedFrame out = Applied(model, 7, 0, 0);
  // Band boundaries at columns 19|20 (1 m -> 2 m) are edges; band interiors are not.
  EXPECT_EQ(out.depth_m.at<float>(60, 19), 0.0f);
  EXPECT_EQ(out.depth_m.at<float>(60, 20), 0.0f);
  EXPECT_GT(out.depth_m.at<float>(60, 10), 0.0f);
  EXPECT_GT(out.depth_m.at<float>(60, 30), 0.0f);
}

TEST(SensorModelTest, RgbNoiseHasTheRequestedSigma) {
  scenes::SensorSpec spec;
  spec.rgb_noise_sigma = 4.0;
  const SensorModel model(spec, kCamera, 10.0, /*fps=*/15.0);
  const RenderedFrame out = Applied(model, 9, 0, 0);
  cv::Mat diff;
  out.color_bgr.convertTo(diff, CV_32FC3);
  diff -= cv::Scalar(128, 128, 128);
  cv::Scalar mean, stddev;
  cv::meanStdDev(diff.reshape(1), mean, stddev);
  EXPECT_NEAR(stddev[0], 4.0, 0.3);
  EXPECT_NEAR(mean[0], 0.0, 0.2);
}

TEST(SensorModelTest, MotionBlurSmearsAlongTheMotion) {
  scenes::SensorSpec spec;
  spec.rgb_noise_sigma = 0;
  spec.motion_blur = true;
  spec.exposure_s = 1.0 / 15;  // the whole frame interval
  const SensorModel model(spec, kCamera, 10.0, 15.0);
  RenderedFrame f = Ramp();
  f.color_bgr.setTo(cv::Scalar(0, 0, 0));
  f.color_bgr.col(80).setTo(cv::Scalar(255, 255, 255));  // a vertical white line
  RenderedFrame still = f;
  still.color_bgr = f.color_bgr.clone();
  // The camera moves 0.2 m along optical x: the scene moves left in the image.
  Eigen::Isometry3d prev = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d cur = Eigen::Isometry3d::Identity();
  cur.translation().x() = 0.2;
  model.Apply(1, 0, 0, prev, cur, &f);
  const cv::Mat row = f.color_bgr.row(60);
  EXPECT_LT(row.at<cv::Vec3b>(0, 80)[0], 255);  // the line is spread out...
  EXPECT_GT(row.at<cv::Vec3b>(0, 78)[0], 0);    // ...horizontally
  EXPECT_EQ(f.color_bgr.at<cv::Vec3b>(60, 40)[0], 0);
  // No motion, no blur.
  model.Apply(1, 0, 0, prev, prev, &still);
  EXPECT_EQ(still.color_bgr.at<cv::Vec3b>(60, 80)[0], 255);
}

}  // namespace
}  // namespace segslam::sim
