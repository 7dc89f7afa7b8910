#include "slam/fast_corners.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "core/error.h"

namespace segslam::slam {
namespace {

// The circle of radius 3 around a pixel, in order around it.
const cv::Point kCircle[16] = {{0, 3},  {1, 3},   {2, 2},   {3, 1},   {3, 0},  {3, -1},
                               {2, -2}, {1, -3},  {0, -3},  {-1, -3}, {-2, -2}, {-3, -1},
                               {-3, 0}, {-3, 1},  {-2, 2},  {-1, 3}};

// What cv::FAST with non-maximum suppression finds in `window` widened by 3 pixels (it
// finds nothing within 3 pixels of its input's edge), in image coordinates.
std::vector<FastCorner> OpenCvCorners(const cv::Mat& image, const cv::Rect& window, int threshold) {
  std::vector<cv::KeyPoint> found;
  const cv::Rect widened(window.x - 3, window.y - 3, window.width + 6, window.height + 6);
  cv::FAST(image(widened), found, threshold, /*nonmaxSuppression=*/true);
  std::vector<FastCorner> corners;
  for (const cv::KeyPoint& k : found) {
    corners.push_back({cvRound(k.pt.x) + widened.x, cvRound(k.pt.y) + widened.y, k.response});
  }
  return corners;
}

std::vector<FastCorner> Corners(const cv::Mat& scores, const cv::Rect& window, int threshold) {
  std::vector<FastCorner> corners;
  AppendFastCorners(scores, window, threshold, &corners);
  return corners;
}

void ExpectSameCorners(const std::vector<FastCorner>& expected, const std::vector<FastCorner>& actual,
                       const std::string& what) {
  ASSERT_EQ(expected.size(), actual.size()) << what;
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(expected[i].x, actual[i].x) << what << ", corner " << i;
    EXPECT_EQ(expected[i].y, actual[i].y) << what << ", corner " << i;
    EXPECT_EQ(expected[i].response, actual[i].response) << what << ", corner " << i;
  }
}

// Images with every kind of neighbourhood FAST meets: noise of every amplitude, hard-edged
// shapes over the whole grey range (saturated contrasts included), smooth blur, flat areas.
std::vector<cv::Mat> TestImages() {
  std::vector<cv::Mat> images;
  cv::RNG rng(20261206);
  cv::Mat noise(97, 131, CV_8U);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  images.push_back(noise);

  cv::Mat shapes(120, 173, CV_8U, cv::Scalar(128));
  for (int i = 0; i < 120; ++i) {
    const cv::Point centre(rng.uniform(0, shapes.cols), rng.uniform(0, shapes.rows));
    const cv::Scalar grey(rng.uniform(0, 2) == 0 ? 255 * rng.uniform(0, 2) : rng.uniform(0, 256));
    if (i % 2 == 0) {
      cv::circle(shapes, centre, rng.uniform(2, 15), grey, cv::FILLED, cv::LINE_AA);
    } else {
      cv::rectangle(shapes, cv::Rect(centre.x, centre.y, rng.uniform(2, 30), rng.uniform(2, 30)), grey,
                    cv::FILLED);
    }
  }
  images.push_back(shapes.clone());

  cv::Mat soft;
  cv::GaussianBlur(shapes, soft, cv::Size(5, 5), 1.2);
  cv::Mat grain(soft.size(), CV_8S);
  rng.fill(grain, cv::RNG::NORMAL, 0, 4);
  cv::add(soft, grain, soft, cv::noArray(), CV_8U);
  soft(cv::Rect(10, 10, 60, 40)).setTo(90);  // flat: no corner at all inside
  images.push_back(soft);
  return images;
}

TEST(FastCornersTest, SinglePixelAndArcsHaveTheirAnalyticScore) {
  cv::Mat image(21, 21, CV_8U, cv::Scalar(100));
  const cv::Rect region(3, 3, 15, 15);
  cv::Mat scores;

  // A bright dot: all 16 circle pixels are 60 darker, so it is a corner up to t = 59.
  image.at<uchar>(10, 10) = 160;
  ComputeFastScores(image, region, 1, &scores);
  EXPECT_EQ(scores.at<uchar>(10, 10), 59);
  ExpectSameCorners({{10, 10, 59.0f}}, Corners(scores, region, 1), "bright dot");
  ExpectSameCorners({}, Corners(scores, region, 60), "bright dot above its score");

  // Arcs around a grey centre: 9 contiguous circle pixels brighter by 40 (and the others
  // equal) make a corner up to t = 39; 8 of them make none.
  for (int arc_length : {9, 8}) {
    for (int start : {0, 5, 13}) {
      image.setTo(100);
      for (int i = 0; i < arc_length; ++i) {
        const cv::Point p = cv::Point(10, 10) + kCircle[(start + i) % 16];
        image.at<uchar>(p) = 140;
      }
      ComputeFastScores(image, region, 1, &scores);
      const std::string what = "arc of " + std::to_string(arc_length) + " from " + std::to_string(start);
      EXPECT_EQ(scores.at<uchar>(10, 10), arc_length == 9 ? 39 : 0) << what;
    }
  }
}

TEST(FastCornersTest, EqualsOpenCvFastOverWholeRegionsAndSmallWindows) {
  for (const cv::Mat& image : TestImages()) {
    const cv::Rect region(3, 3, image.cols - 6, image.rows - 6);
    for (int min_threshold : {1, 7, 20}) {
      cv::Mat scores;
      ComputeFastScores(image, region, min_threshold, &scores);
      for (int threshold : {min_threshold, min_threshold + 1, 20, 45, 120, 200}) {
        const std::string what = "image " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                                 ", min threshold " + std::to_string(min_threshold) + ", threshold " +
                                 std::to_string(threshold);
        ExpectSameCorners(OpenCvCorners(image, region, threshold), Corners(scores, region, threshold),
                          what + ", whole region");
        // Windows as the ORB extractor's cells, their edges where a window's border
        // suppresses nothing that lies outside it, and thin and tiny ones.
        const cv::Rect windows[] = {
            cv::Rect(3, 3, 30, 30), cv::Rect(33, 3, 30, 31),
            cv::Rect(region.x + region.width - 17, region.y + region.height - 9, 17, 9),
            cv::Rect(40, 20, 1, 50), cv::Rect(20, 40, 50, 1), cv::Rect(50, 50, 2, 2)};
        for (const cv::Rect& window : windows) {
          const std::string where = ", window at (" + std::to_string(window.x) + ", " +
                                    std::to_string(window.y) + ") " + std::to_string(window.width) +
                                    "x" + std::to_string(window.height);
          ExpectSameCorners(OpenCvCorners(image, window, threshold), Corners(scores, window, threshold),
                            what + where);
        }
      }
    }
  }
}

TEST(FastCornersTest, RegionsNarrowerThanAVectorAndOffsetRegionsScoreAlike) {
  // Rows shorter than a vector span are scored pixel by pixel, rows of odd lengths with
  // one overlapping span at their end: every pixel's score must not depend on how.
  const cv::Mat image = TestImages()[0];
  cv::Mat whole;
  ComputeFastScores(image, cv::Rect(3, 3, image.cols - 6, image.rows - 6), 1, &whole);
  for (const cv::Rect& region : {cv::Rect(3, 3, 5, 20), cv::Rect(10, 4, 17, 9), cv::Rect(7, 30, 33, 3),
                                 cv::Rect(4, 40, 71, 2)}) {
    cv::Mat part;
    ComputeFastScores(image, region, 1, &part);
    EXPECT_EQ(cv::norm(part(region), whole(region), cv::NORM_INF), 0.0);
    cv::Mat outside = part.clone();
    outside(region).setTo(0);
    EXPECT_EQ(cv::countNonZero(outside), 0) << "scores outside the region must be 0";
  }
}

TEST(FastCornersTest, RejectsRegionsTooNearTheEdgeAndWrongInput) {
  const cv::Mat image(40, 50, CV_8U, cv::Scalar(0));
  cv::Mat scores;
  EXPECT_THROW(ComputeFastScores(image, cv::Rect(2, 3, 10, 10), 7, &scores), Error);
  EXPECT_THROW(ComputeFastScores(image, cv::Rect(3, 3, 45, 10), 7, &scores), Error);
  EXPECT_THROW(ComputeFastScores(image, cv::Rect(3, 3, 0, 10), 7, &scores), Error);
  EXPECT_THROW(ComputeFastScores(image, cv::Rect(3, 3, 10, 10), 0, &scores), Error);
  EXPECT_THROW(ComputeFastScores(cv::Mat(40, 50, CV_16U), cv::Rect(3, 3, 10, 10), 7, &scores), Error);
  EXPECT_NO_THROW(ComputeFastScores(image, cv::Rect(3, 3, 44, 34), 7, &scores));
}

}  // namespace
}  // namespace segslam::slam
