#include "harness/pictures.h"

#include <opencv2/imgproc.hpp>

namespace segslam::harness {
namespace {

// A stable, well-spread colour per instance id (Knuth's multiplicative hash).
cv::Vec3b InstanceColor(std::uint16_t id) {
  const unsigned hash = id * 2654435761u;
  return {static_cast<uchar>(64 + (hash & 0x7f)), static_cast<uchar>(64 + ((hash >> 8) & 0x7f)),
          static_cast<uchar>(64 + ((hash >> 16) & 0x7f))};
}

}  // namespace

cv::Mat DepthPicture(const cv::Mat& depth_m, double max_depth_m) {
  cv::Mat scaled;
  depth_m.convertTo(scaled, CV_8U, 255.0 / max_depth_m);
  cv::Mat colored;
  cv::applyColorMap(scaled, colored, cv::COLORMAP_TURBO);
  colored.setTo(cv::Scalar(0, 0, 0), depth_m == 0.f);
  return colored;
}

cv::Mat OverlayPicture(const cv::Mat& color_bgr, const cv::Mat& ids) {
  cv::Mat overlay = color_bgr.clone();
  for (int v = 0; v < ids.rows; ++v) {
    for (int u = 0; u < ids.cols; ++u) {
      const std::uint16_t id = ids.at<std::uint16_t>(v, u);
      if (id == 0) continue;
      cv::Vec3b& pixel = overlay.at<cv::Vec3b>(v, u);
      const cv::Vec3b tint = InstanceColor(id);
      // Outline pixels (a neighbour has another id) are drawn solid.
      const bool edge = (u > 0 && ids.at<std::uint16_t>(v, u - 1) != id) ||
                        (v > 0 && ids.at<std::uint16_t>(v - 1, u) != id) ||
                        (u + 1 < ids.cols && ids.at<std::uint16_t>(v, u + 1) != id) ||
                        (v + 1 < ids.rows && ids.at<std::uint16_t>(v + 1, u) != id);
      for (int c = 0; c < 3; ++c) {
        pixel[c] = edge ? tint[c] : static_cast<uchar>((pixel[c] + 2 * tint[c]) / 3);
      }
    }
  }
  return overlay;
}

cv::Mat CaptionedRow(const std::vector<cv::Mat>& images, const std::vector<std::string>& captions) {
  std::vector<cv::Mat> captioned;
  for (size_t i = 0; i < images.size(); ++i) {
    cv::Mat image = images[i].clone();
    if (i < captions.size()) {
      cv::putText(image, captions[i], {8, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.55, {0, 0, 0}, 3,
                  cv::LINE_AA);
      cv::putText(image, captions[i], {8, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.55, {255, 255, 255}, 1,
                  cv::LINE_AA);
    }
    captioned.push_back(image);
  }
  cv::Mat row;
  cv::hconcat(captioned, row);
  return row;
}

}  // namespace segslam::harness
