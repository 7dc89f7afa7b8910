// Pictures for people: colour-mapped depth, instance overlays, labelled rows.
#pragma once

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace segslam::harness {

// Depth (CV_32F metres) as a turbo colour map over [0, max_depth_m]; no depth is black.
cv::Mat DepthPicture(const cv::Mat& depth_m, double max_depth_m);

// The colour image with each instance of `ids` (CV_16U, 0 = none) tinted in a colour
// that depends only on its id, and outlined.
cv::Mat OverlayPicture(const cv::Mat& color_bgr, const cv::Mat& ids);

// Images of one height side by side, each with its caption in the top-left corner.
cv::Mat CaptionedRow(const std::vector<cv::Mat>& images, const std::vector<std::string>& captions);

}  // namespace segslam::harness
