#include "core/lens_distortion.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "core/error.h"
#include "test_util.h"

namespace segslam {
namespace {

using testing::ErrorMessage;

// TUM's freiburg1 colour camera: 17 to 37 px of distortion at the image corners.
PinholeCamera Freiburg1Camera() { return {640, 480, 517.3, 516.5, 318.6, 255.3}; }
LensDistortion Freiburg1Distortion() { return {0.2624, -0.9531, -0.0054, 0.0026, 1.1633}; }

cv::Vec2d PixelWhereTheLensPuts(const PinholeCamera& camera, const LensDistortion& distortion,
                                const cv::Vec2d& pinhole_pixel) {
  const cv::Vec2d d = distortion.Distort(
      {(pinhole_pixel[0] - camera.cx) / camera.fx, (pinhole_pixel[1] - camera.cy) / camera.fy});
  return {camera.fx * d[0] + camera.cx, camera.fy * d[1] + camera.cy};
}

// Centroid of each nonzero id.
std::map<int, cv::Vec2d> Centroids(const cv::Mat& ids) {
  std::map<int, cv::Vec3d> sums;
  for (int v = 0; v < ids.rows; ++v) {
    for (int u = 0; u < ids.cols; ++u) {
      const int id = ids.at<std::uint16_t>(v, u);
      if (id != 0) sums[id] += cv::Vec3d(u, v, 1);
    }
  }
  std::map<int, cv::Vec2d> centroids;
  for (const auto& [id, sum] : sums) centroids[id] = {sum[0] / sum[2], sum[1] / sum[2]};
  return centroids;
}

// Intensity-weighted centroid of a grey image within 12 px of `near`.
cv::Vec2d WeightedCentroid(const cv::Mat& grey, const cv::Vec2d& near) {
  cv::Vec3d sum(0, 0, 0);
  for (int v = static_cast<int>(near[1]) - 12; v <= static_cast<int>(near[1]) + 12; ++v) {
    for (int u = static_cast<int>(near[0]) - 12; u <= static_cast<int>(near[0]) + 12; ++u) {
      if (u < 0 || v < 0 || u >= grey.cols || v >= grey.rows) continue;
      const double w = grey.at<float>(v, u);
      sum += cv::Vec3d(w * u, w * v, w);
    }
  }
  return {sum[0] / sum[2], sum[1] / sum[2]};
}

TEST(LensDistortionTest, DistortAgreesWithOpenCvsProjection) {
  const PinholeCamera camera = Freiburg1Camera();
  const LensDistortion distortion = Freiburg1Distortion();
  std::vector<cv::Point3d> points;
  for (double x = -0.62; x <= 0.62; x += 0.155) {
    for (double y = -0.5; y <= 0.5; y += 0.125) points.emplace_back(2 * x, 2 * y, 2.0);
  }
  std::vector<cv::Point2d> projected;
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera.KCv(), distortion.Coefficients(),
                    projected);
  for (size_t k = 0; k < points.size(); ++k) {
    const cv::Vec2d ours = PixelWhereTheLensPuts(
        camera, distortion, {camera.fx * points[k].x / 2 + camera.cx, camera.fy * points[k].y / 2 + camera.cy});
    EXPECT_NEAR(ours[0], projected[k].x, 1e-9);
    EXPECT_NEAR(ours[1], projected[k].y, 1e-9);
  }
  EXPECT_TRUE(LensDistortion{}.IsZero());
  EXPECT_FALSE(distortion.IsZero());
}

TEST(LensDistortionTest, ResamplingMovesEachSpotWhereTheLensPutsItAndBack) {
  const PinholeCamera camera = Freiburg1Camera();
  const LensDistortion distortion = Freiburg1Distortion();
  const ImageUndistorter undistorter(camera, distortion);

  // Spots on a grid over the pinhole image, out to 30 px from its edges: 7x7-pixel
  // labelled squares, and Gaussian blobs (sigma 3 px) in a grey image.
  cv::Mat pinhole_ids(480, 640, CV_16UC1, cv::Scalar(0));
  cv::Mat pinhole_grey(480, 640, CV_32FC1, cv::Scalar(0));
  std::map<int, cv::Vec2d> spots;
  int id = 1;
  for (int v = 30; v <= 450; v += 60) {
    for (int u = 30; u <= 610; u += 58, ++id) {
      pinhole_ids(cv::Rect(u - 3, v - 3, 7, 7)).setTo(id);
      for (int dv = -10; dv <= 10; ++dv) {
        for (int du = -10; du <= 10; ++du) {
          pinhole_grey.at<float>(v + dv, u + du) = static_cast<float>(std::exp(-(du * du + dv * dv) / 18.0));
        }
      }
      spots[id] = {static_cast<double>(u), static_cast<double>(v)};
    }
  }

  const cv::Mat stored_ids = undistorter.DistortIds(pinhole_ids);
  const std::map<int, cv::Vec2d> stored = Centroids(stored_ids);
  const std::map<int, cv::Vec2d> back = Centroids(undistorter.UndistortIds(stored_ids));
  const cv::Mat stored_grey = undistorter.DistortColour(pinhole_grey);
  const cv::Mat back_grey = undistorter.UndistortColour(stored_grey);
  double largest_shift_px = 0;
  for (const auto& [spot, pinhole_px] : spots) {
    const cv::Vec2d expected = PixelWhereTheLensPuts(camera, distortion, pinhole_px);
    // Nearest-pixel ids: each edge of a square may move by up to half a pixel.
    ASSERT_EQ(stored.count(spot), 1u) << "spot " << spot << " left the stored image";
    EXPECT_LT(cv::norm(stored.at(spot) - expected), 0.75) << "spot at " << pinhole_px;
    ASSERT_EQ(back.count(spot), 1u);
    EXPECT_LT(cv::norm(back.at(spot) - pinhole_px), 0.75) << "spot at " << pinhole_px;
    // Interpolated grey: sub-pixel.
    EXPECT_LT(cv::norm(WeightedCentroid(stored_grey, expected) - expected), 0.15) << "spot at " << pinhole_px;
    EXPECT_LT(cv::norm(WeightedCentroid(back_grey, pinhole_px) - pinhole_px), 0.15) << "spot at " << pinhole_px;
    largest_shift_px = std::max(largest_shift_px, cv::norm(expected - pinhole_px));
  }
  // The check means something: the lens moves the outer spots by many pixels.
  EXPECT_GT(largest_shift_px, 10.0);
}

TEST(LensDistortionTest, DepthAndIdsKeepTheirValuesColourHasNoEdgeAtTheBorder) {
  const PinholeCamera camera = Freiburg1Camera();
  const ImageUndistorter undistorter(camera, Freiburg1Distortion());
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(1.0f));
  depth(cv::Rect(0, 0, 320, 480)).setTo(2.5f);
  const cv::Mat undistorted_depth = undistorter.UndistortDepth(depth);
  std::set<float> values(undistorted_depth.begin<float>(), undistorted_depth.end<float>());
  EXPECT_EQ(values, (std::set<float>{0.0f, 1.0f, 2.5f}));  // Nearest pixel: no blend of 1 and 2.5.
  // The pinhole image's corners lie outside what the lens saw: no depth there.
  EXPECT_EQ(undistorted_depth.at<float>(0, 0), 0.0f);
  EXPECT_EQ(undistorted_depth.at<float>(240, 320), 1.0f);

  const cv::Mat colour(480, 640, CV_8UC3, cv::Scalar(40, 80, 120));
  const cv::Mat undistorted_colour = undistorter.UndistortColour(colour);
  EXPECT_EQ(undistorted_colour.type(), CV_8UC3);
  EXPECT_EQ(cv::norm(undistorted_colour, colour, cv::NORM_INF), 0.0);  // Border replicated.
}

// k3 = -1 stops bending outwards at normalised radius 0.723, inside the corners of a
// Kinect-like image (0.76), where it has bent a point to 0.62 at most: beyond, the model
// folds back, and the pixels it would give are left empty rather than filled wrongly.
TEST(LensDistortionTest, PixelsBeyondWhereTheLensFoldsStayEmpty) {
  const PinholeCamera camera{640, 480, 525, 525, 319.5, 239.5};
  const LensDistortion folding{0, 0, 0, 0, -1};
  EXPECT_NEAR(folding.GrowingRadius(1.0), std::pow(1.0 / 7.0, 1.0 / 6.0), 1e-3);
  EXPECT_EQ(Freiburg1Distortion().GrowingRadius(0.8), 0.8);  // Grows over the whole image.
  const ImageUndistorter undistorter(camera, folding);
  const cv::Mat ones(480, 640, CV_32F, cv::Scalar(1.0f));
  // The pixel on the image's diagonal at normalised radius r.
  auto at = [&](const cv::Mat& image, double r) {
    const double d = r / std::hypot(319.5 / 525, 239.5 / 525);
    return image.at<float>(static_cast<int>(std::lround(239.5 * (1 - d))), static_cast<int>(std::lround(319.5 * (1 - d))));
  };
  const cv::Mat undistorted = undistorter.UndistortDepth(ones);
  EXPECT_EQ(at(undistorted, 0.70), 1.0f);  // modelled, bent to 0.62: inside the stored image
  EXPECT_EQ(at(undistorted, 0.75), 0.0f);  // beyond the fold
  const cv::Mat distorted = undistorter.DistortDepth(ones);
  EXPECT_EQ(at(distorted, 0.60), 1.0f);    // the bend of a point at 0.64
  EXPECT_EQ(at(distorted, 0.70), 0.0f);    // no point within the fold bends this far out
}

TEST(LensDistortionTest, NoDistortionLeavesImagesAsTheyAre) {
  const PinholeCamera camera{64, 48, 60, 60, 31.5, 23.5};
  const ImageUndistorter undistorter(camera, LensDistortion{});
  cv::Mat ids(48, 64, CV_16UC1);
  cv::randu(ids, 0, 5);
  EXPECT_EQ(cv::norm(undistorter.UndistortIds(ids), ids, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(undistorter.DistortIds(ids), ids, cv::NORM_INF), 0.0);
}

TEST(LensDistortionTest, BadInputIsNamed) {
  const PinholeCamera camera = Freiburg1Camera();
  LensDistortion broken = Freiburg1Distortion();
  broken.p2 = std::nan("");
  EXPECT_NE(ErrorMessage([&] { ImageUndistorter(camera, broken); }).find("must be finite"), std::string::npos);
  const ImageUndistorter undistorter(camera, Freiburg1Distortion());
  const std::string message =
      ErrorMessage([&] { undistorter.UndistortDepth(cv::Mat(240, 320, CV_32F, cv::Scalar(1.0f))); });
  EXPECT_NE(message.find("image is 320x240, the camera's is 640x480"), std::string::npos) << message;
}

}  // namespace
}  // namespace segslam
