// The one way a frame goes through segslam, for every mode (mutual/slam_mode.h): the
// paper's per-frame mutual loop (its Fig. 1; DESIGN.md "The core") and the baselines it
// is measured against, which are the same loop with steps left out.
//
// Per frame t (ProcessFrame):
//   1. initial instances from the segmenter (every mode but plain);
//      mask-moveable drops every feature on a moveable-class instance here;
//   2. coarse pose T_c(t) (slam::Tracker::EstimateCoarsePose);
//   3. mutual: refinement (seg::SegmentationRefiner) of the initial instances from the
//      refined instances and depth of frame t-1, with T_cur_prev = T_c(t)^-1 * T_f(t-1);
//   4. mutual and oracle: moving/static judgement of the (refined) instances, the
//      oracle taking the ground truth's verdicts; then, every mode, the fine pose T_f(t)
//      from what is kept and the map updates (keyframes, points, local BA);
//   5. the refined instances and depth of t are kept for t+1.
// Without a previous fine pose (first frame, or frame t-1 lost) or without a coarse pose
// (frame t lost) nothing can be projected: the refiner is called without a previous
// frame, so the initial instances come back as they are, with fresh ids from the same
// refiner (ids are never reused within a run).
//
// Moving objects are projected with the camera's motion only, as in the paper: an own
// rigid motion per moving instance gained nothing measurable (docs/tuning.md).
//
// A pass's start is judged in hindsight (TrackerOptions::retrack_map_start): nothing can
// be judged in its first motion_baseline_s, so every moveable instance in view is kept out
// of the founding keyframes. At the first frame a baseline on, if an instance kept out
// unjudged there is now judged still, those frames are tracked again from the start by a
// fresh tracker given the verdicts (slam::Tracker::PresetStartVerdicts), with the same
// refined masks; their results replace the first ones in frames() and trajectory().
//
// The pipeline also keeps the run's record: each frame's result, and the trajectory of
// the localized frames. A map reset voids the poses before it (they are in the frame of
// a map that no longer exists), so those frames count as lost, as ORB-SLAM2 forgets them.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "core/camera.h"
#include "core/frame.h"
#include "core/pose.h"
#include "mutual/slam_mode.h"
#include "seg/ground_truth.h"
#include "seg/refiner.h"
#include "seg/segmentation.h"
#include "seg/segmenter.h"
#include "slam/map_file.h"
#include "slam/tracker.h"

namespace segslam::mutual {

struct FramePipelineOptions {
  SlamMode mode = SlamMode::kMutual;
  // Mutual mode: refine the segmenter's masks from the previous frame (step 3). Off for
  // the ground truth's masks, which have nothing to repair; ignored by the other modes.
  bool refine_masks = true;
  slam::TrackerOptions tracker;
  seg::RefinerOptions refiner;
};

struct FrameStep {
  slam::FrameResult slam;          // the tracker's result (fine pose, judgements)
  seg::FrameSegmentation initial;  // the segmenter's instances (none in plain mode)
  seg::FrameSegmentation refined;  // what SLAM judged: the refined instances, or the initial ones
  bool refined_in_loop = false;    // step 3 ran (mutual with refine_masks)
  // Step 3 projected frame t-1 (false: first or lost frame, or the previous frame was
  // lost; then refined = initial with fresh ids).
  bool refined_from_previous = false;
  std::vector<seg::RegionDecision> decisions;
  double segment_ms = 0;
  double refine_ms = 0;
};

// The refined instances as slam/ takes them: the id image (FrameSegmentation::ToIdImage)
// and the ids of moveable COCO classes (core/coco.h).
slam::FrameInstances ToFrameInstances(const seg::FrameSegmentation& segmentation, cv::Size size);

// Not copyable: it owns the tracker's maps and the refiner's id counter.
class FramePipeline {
 public:
  // `segmenter` gives the initial instances and must outlive the pipeline; null only in
  // plain mode. `motion` (the ground truth's verdicts) is needed by the oracle only. Throws
  // segslam::Error on invalid refiner options or a segmenter or motion the mode lacks.
  FramePipeline(const PinholeCamera& camera, const FramePipelineOptions& options, seg::Segmenter* segmenter,
                const seg::GroundTruthMotion* motion = nullptr);
  FramePipeline(const FramePipeline&) = delete;
  FramePipeline& operator=(const FramePipeline&) = delete;

  // Localization mode (the second pass), see slam::Tracker::LoadLongTermMap.
  void LoadLongTermMap(const slam::LongTermMapData& map, const std::string& origin);

  // One frame (see the file comment). Throws segslam::Error on a frame or masks of the
  // wrong type or size (from the tracker, segmenter or refiner). Where the pass's start is
  // tracked again, the steps returned for its earlier frames hold their first tries:
  // frames() holds what counts.
  FrameStep ProcessFrame(const RgbdFrame& frame);

  // Every frame processed so far, the frames before a map reset marked lost.
  const std::vector<slam::FrameResult>& frames() const { return frames_; }
  // T_wc of the localized frames since the last map reset.
  const std::vector<StampedPose>& trajectory() const { return trajectory_; }

  // The long-term map (DESIGN.md core step 5) as the mode keeps it: plain knows no
  // instances, so everything it mapped; mask-moveable never mapped a moveable object;
  // mutual and the oracle keep the background and the fixed-class instances, no point on
  // a moveable one (TrackerOptions::long_term_map_keeps_fixed_instances).
  slam::LongTermMapData ExportLongTermMap() const;

  const slam::Tracker& tracker() const { return *tracker_; }
  const FramePipelineOptions& options() const { return options_; }

 private:
  bool RefinesMasks() const { return IsMutualLoop(options_.mode) && options_.refine_masks; }
  void Refine(const RgbdFrame& frame, const std::optional<Eigen::Isometry3d>& T_wc_coarse, FrameStep* step);
  void Record(const slam::FrameResult& frame);
  // The map's start in hindsight (file comment): keeps frame t while the start lasts and,
  // at its end, re-tracks it where a verdict would change it (step->slam becomes the
  // re-tracked result of frame t).
  void RememberMapStart(const RgbdFrame& frame, const slam::FrameInstances& instances, FrameStep* step);
  bool StartWorthRetracking() const;
  void RetrackMapStart(FrameStep* step);

  struct StartFrame {
    RgbdFrame frame;                  // its own copy of the images
    slam::FrameInstances instances;   // the refined instances the tracker judged
  };

  PinholeCamera camera_;
  FramePipelineOptions options_;
  seg::Segmenter* segmenter_;
  const seg::GroundTruthMotion* motion_;
  std::unique_ptr<slam::Tracker> tracker_;  // replaced when the start is re-tracked
  std::string long_term_map_origin_;
  // The pass's first motion_baseline_s, while it lasts (RememberMapStart).
  std::vector<StartFrame> start_frames_;
  bool at_start_ = false;
  seg::SegmentationRefiner refiner_;
  // Frame t-1, for the refinement of frame t.
  std::optional<seg::FrameSegmentation> previous_refined_;
  cv::Mat previous_depth_m_;
  std::optional<Eigen::Isometry3d> previous_T_wc_fine_;  // nullopt when t-1 was lost
  std::vector<slam::FrameResult> frames_;
  std::vector<StampedPose> trajectory_;
};

}  // namespace segslam::mutual
