// Instance segmentation of one frame, as every segmenter returns it and as the
// refinement of the paper (seg/refiner.h) consumes and produces it.
//
// Images: masks are CV_8U, the frame's size, 1 inside the instance and 0 outside.
// Ids: `track_id` is a per-sequence identity; a segmenter may number its detections
// freely, the refiner makes ids stable over time where its matching says so.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace segslam::seg {

struct InstanceMask {
  std::uint16_t track_id = 0;  // >= 1; 0 is never an instance
  int category_id = 0;         // COCO category id (core/coco.h)
  float score = 1.0f;          // confidence in [0, 1]; AP ranks detections by it
  cv::Mat mask;                // CV_8U, frame-sized, 1 = instance pixel
  // A rectangle that holds every pixel of `mask`, as a detector's box does; empty = not
  // known (the whole frame). Readers look only inside it, so whoever writes `mask` keeps
  // it true: a mask pixel outside it is not seen. It need not be tight.
  cv::Rect bounds;
};

// Where to look for the instance's pixels: its bounds within the mask, else the mask.
cv::Rect SearchBox(const InstanceMask& instance);

// Sets instance->bounds to the bounding box of its mask's pixels (empty when none); reads
// the whole mask. For producers that do not know a box.
void FitBounds(InstanceMask* instance);

// Whether every pixel of the mask lies inside SearchBox (reads the whole mask; for the
// tests of a producer).
bool BoundsHoldMask(const InstanceMask& instance);

struct FrameSegmentation {
  int frame_index = 0;
  std::vector<InstanceMask> instances;

  // A 16-bit id image (CV_16U, 0 = background) of the instances; where masks overlap
  // the higher-scoring instance wins. `size` is the frame size.
  cv::Mat ToIdImage(cv::Size size) const;
};

}  // namespace segslam::seg
