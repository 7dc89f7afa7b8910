// One interface for every source of initial instance segmentations: the simulated
// segmenter on synthetic data (seg/simulated_segmenter.h) and masks computed by an
// external network (seg/external_masks.h).
#pragma once

#include "core/frame.h"
#include "seg/segmentation.h"

#include <string>

namespace segslam::seg {

class Segmenter {
 public:
  virtual ~Segmenter() = default;
  // Instances of `frame` (frame.index identifies it in the sequence). Deterministic:
  // the same frame gives the same result, whatever was asked before.
  virtual FrameSegmentation Segment(const RgbdFrame& frame) = 0;
  // A short name for reports, e.g. "fcis-like" or "external:/data/masks".
  virtual std::string name() const = 0;
};

}  // namespace segslam::seg
