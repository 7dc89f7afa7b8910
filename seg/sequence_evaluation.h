// Raw vs refined instance segmentation over one generated sequence with ground-truth
// poses (the paper's Tables II and IV): runs a segmenter on every frame, refines each
// frame from the previous refined one (seg/refiner.h) with the true camera poses (and,
// optionally, the true motion of moving objects), and scores both against the
// ground-truth instance masks (seg/metrics.h). `segslam seg-eval` prints it; the
// dataset tests assert it.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "core/tracks.h"

#include "seg/metrics.h"
#include "seg/refiner.h"
#include "seg/segmentation.h"
#include "seg/segmenter.h"

namespace segslam::seg {

struct SegEvalOptions {
  RefinerOptions refiner;
  // Project a moving object's region with its own ground-truth motion (from the
  // sequence's tracks.json, the region's instance being the ground-truth id it overlaps
  // most); false: with the camera motion only, as the paper does.
  bool object_motion = true;
  // Called after each frame with (frames done, frames in all); may throw to cancel.
  std::function<void(int, int)> on_frame;
};

struct SequenceSegEval {
  std::string name;  // the sequence folder's name, e.g. "pass1"
  int frames = 0;
  SegmentationScores raw;      // the segmenter's instances
  SegmentationScores refined;  // after the refinement
  // The segmenter's instances scoring at least the refiner's min_new_region_score: the
  // refinement drops new regions under it, so this is the baseline without the refiner's
  // use of the previous frame (what a plain score threshold alone gives).
  SegmentationScores raw_confident;
  double raw_confident_min_score = 0;
  double refine_ms_median = 0;
  // RegionDecision kinds summed over the sequence, indexed by RegionDecision::Kind.
  std::array<int, 5> decision_counts{};
  // The last frame (for the paper's Fig. 5): colour, ground-truth ids (CV_16U), the
  // segmenter's and the refined instances.
  cv::Mat last_color_bgr;
  cv::Mat last_gt_ids;
  FrameSegmentation last_initial;
  FrameSegmentation last_refined;
};

// Evaluates the sequence in `sequence_dir` (a TUM-format sequence with masks/,
// instances.json, one ground-truth pose per frame, and optionally tracks.json).
// Throws segslam::Error (FileError) on missing ground truth or any reader's error.
SequenceSegEval EvaluateSequenceWithGroundTruthPoses(const SegEvalOptions& options,
                                                      const std::filesystem::path& sequence_dir,
                                                      Segmenter& segmenter);

// The ground-truth tracks by instance id.
using TrackIndex = std::map<std::uint16_t, const ObjectTrack*>;

// The motion from frame `frame` - 1 to `frame` of each previous region's ground-truth
// object, by the region's track id, as the refiner projects it: T_cur_prev = T_cw(t)
// T_wo(t) T_ow(t-1) T_wc(t-1), with every pose the true one (for an object that stands
// still, the camera's motion alone). A region is the object it overlaps most in
// previous_gt; a region over no object, or over one absent from either frame, has none.
std::map<std::uint16_t, Eigen::Isometry3d> GroundTruthRegionMotions(const FrameSegmentation& previous_refined,
                                                                    const cv::Mat& previous_gt,
                                                                    const TrackIndex& track_of, int frame,
                                                                    const Eigen::Isometry3d& T_wc_previous,
                                                                    const Eigen::Isometry3d& T_wc_current);

}  // namespace segslam::seg
