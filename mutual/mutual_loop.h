// The paper's per-frame mutual loop (its Fig. 1; DESIGN.md "The core"): SLAM's coarse
// pose lets the segmentation of frame t be refined from the refined segmentation of
// frame t-1, and the refined masks let SLAM tell moving from static instances for its
// fine pose and its maps.
//
// Per frame t:
//   1. initial instances from the segmenter;
//   2. coarse pose T_c(t) (slam::Tracker::EstimateCoarsePose);
//   3. refinement (seg::SegmentationRefiner) of the initial instances from the refined
//      instances and depth of frame t-1, with T_cur_prev = T_c(t)^-1 * T_f(t-1);
//   4. moving/static judgement of the refined instances, fine pose T_f(t), map updates;
//   5. the refined instances and depth of t are kept for t+1.
// Without a previous fine pose (first frame, or frame t-1 lost) or without a coarse pose
// (frame t lost) nothing can be projected: the refiner is called without a previous
// frame, so the initial instances come back as they are, with fresh ids from the same
// refiner (ids are never reused within a loop).
//
// Moving objects are projected with the camera's motion only, as in the paper: an own
// rigid motion per moving instance gained nothing measurable (docs/tuning.md).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "core/camera.h"
#include "core/frame.h"
#include "seg/refiner.h"
#include "seg/segmentation.h"
#include "seg/segmenter.h"
#include "slam/map_file.h"
#include "slam/tracker.h"

namespace segslam::mutual {

struct MutualLoopOptions {
  slam::TrackerOptions tracker;
  seg::RefinerOptions refiner;
};

struct MutualFrameResult {
  slam::FrameResult slam;               // the tracker's result (fine pose, judgements)
  seg::FrameSegmentation initial;       // the segmenter's instances of the frame
  seg::FrameSegmentation refined;       // after the refinement; what SLAM judged
  // True when the refinement projected frame t-1 (false: first or lost frame, or the
  // previous frame was lost; then refined = initial with fresh ids).
  bool refined_from_previous = false;
  std::vector<seg::RegionDecision> decisions;
  double segment_ms = 0;
  double refine_ms = 0;
};

// The refined instances as slam/ takes them: the id image (FrameSegmentation::ToIdImage)
// and the ids of moveable COCO classes (core/coco.h).
slam::FrameInstances ToFrameInstances(const seg::FrameSegmentation& segmentation, cv::Size size);

// Not copyable: it owns the tracker's maps and the refiner's id counter.
class MutualLoop {
 public:
  // `segmenter` gives the initial instances and must outlive the loop. Throws
  // segslam::Error on invalid refiner options.
  MutualLoop(const PinholeCamera& camera, seg::Segmenter& segmenter,
             const MutualLoopOptions& options = {});
  MutualLoop(const MutualLoop&) = delete;
  MutualLoop& operator=(const MutualLoop&) = delete;

  // Localization mode (the second pass), see slam::Tracker::LoadLongTermMap.
  void LoadLongTermMap(const slam::LongTermMapData& map, const std::string& origin);

  // One frame of the loop (see the file comment). Throws segslam::Error on a frame or
  // masks of the wrong type or size (from the tracker, segmenter or refiner).
  MutualFrameResult ProcessFrame(const RgbdFrame& frame);

  const slam::Tracker& tracker() const { return tracker_; }
  const MutualLoopOptions& options() const { return options_; }

 private:
  PinholeCamera camera_;
  seg::Segmenter& segmenter_;
  MutualLoopOptions options_;
  slam::Tracker tracker_;
  seg::SegmentationRefiner refiner_;
  // Frame t-1, for the refinement of frame t.
  std::optional<seg::FrameSegmentation> previous_refined_;
  cv::Mat previous_depth_m_;
  std::optional<Eigen::Isometry3d> previous_T_wc_fine_;  // nullopt when t-1 was lost
};

}  // namespace segslam::mutual
