// One RGB-D frame as the rest of segslam sees it.
#pragma once

#include <opencv2/core/mat.hpp>

namespace segslam {

struct RgbdFrame {
  int index = 0;       // Position in the sequence, 0-based.
  double stamp_s = 0;  // Timestamp in seconds (the colour image's, for TUM data).
  cv::Mat color_bgr;   // CV_8UC3, BGR.
  cv::Mat depth_m;     // CV_32F, metres along the optical axis, 0 = no depth;
                       // registered to color_bgr (same size, same camera).
};

}  // namespace segslam
