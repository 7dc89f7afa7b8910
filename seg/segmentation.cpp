#include "seg/segmentation.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <numeric>

namespace segslam::seg {

cv::Mat FrameSegmentation::ToIdImage(cv::Size size) const {
  cv::Mat ids(size, CV_16U, cv::Scalar(0));
  // Paint from the lowest to the highest score so the best-scored instance wins overlaps.
  std::vector<size_t> order(instances.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return instances[a].score < instances[b].score;
  });
  for (size_t i : order) {
    const InstanceMask& instance = instances[i];
    CV_Assert(instance.mask.type() == CV_8U && instance.mask.size() == size);
    const cv::Rect box = SearchBox(instance);
    ids(box).setTo(instance.track_id, instance.mask(box));
  }
  return ids;
}

cv::Rect SearchBox(const InstanceMask& instance) {
  const cv::Rect frame(0, 0, instance.mask.cols, instance.mask.rows);
  return instance.bounds.empty() ? frame : (instance.bounds & frame);
}

void FitBounds(InstanceMask* instance) { instance->bounds = cv::boundingRect(instance->mask); }

bool BoundsHoldMask(const InstanceMask& instance) {
  const cv::Rect pixels = cv::boundingRect(instance.mask);
  return pixels.empty() || (pixels & SearchBox(instance)) == pixels;
}

}  // namespace segslam::seg
