// FAST-9 corners (Rosten and Drummond's segment test on the 16-pixel circle of radius 3)
// found the way cv::FAST finds them with non-maximum suppression, but from one score map
// per image: ORB extraction asks for corners at two thresholds and in many small windows
// (orb_extractor.cpp), and scoring each pixel once costs less than a cv::FAST call per
// window, whose small windows run mostly outside its vector loop.
#pragma once

#include <opencv2/core/mat.hpp>
#include <opencv2/core/types.hpp>
#include <vector>

namespace segslam::slam {

struct FastCorner {
  int x = 0;  // image pixel coordinates
  int y = 0;
  float response = 0;  // the FAST score, as cv::KeyPoint::response of cv::FAST
};

// The FAST score of every pixel of `region` into `scores` (CV_8U, the image's size, zero
// outside the region): the largest threshold t at which the pixel is a FAST-9 corner, that
// is, at which 9 contiguous circle pixels are all brighter than centre + t or all darker
// than centre - t; 0 where that is below min_threshold (such a pixel is no corner at any
// threshold asked for later, and no neighbour's maximum depends on it). `image` is CV_8U;
// `region` keeps 3 pixels from its edges; 1 <= min_threshold <= 254. Throws
// segslam::Error otherwise.
void ComputeFastScores(const cv::Mat& image, const cv::Rect& region, int min_threshold,
                       cv::Mat* scores);

// Appends, row by row, the pixels of `window` whose score is at least `threshold` and
// strictly greater than that of each of their 8 neighbours inside the window: exactly the
// corners, in the same order and with the same responses, that cv::FAST(image(window
// widened by 3 pixels), threshold, nonmaxSuppression=true) gives, shifted to image
// coordinates, for any threshold >= the scores' min_threshold. `window` lies inside the
// scored region.
void AppendFastCorners(const cv::Mat& scores, const cv::Rect& window, int threshold,
                       std::vector<FastCorner>* corners);

}  // namespace segslam::slam
