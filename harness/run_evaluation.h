// Scores the outputs of `segslam run` (harness/dataset_run.h) against a dataset's ground
// truth: what `segslam eval` prints and `segslam scenario run` aggregates over repeats.
//
// Per pass (pass1/ and pass2/ of a two-pass run, or the single sequence):
// - ATE as evaluate_ate.py (harness/trajectory_metrics.h). Pass 1 (or a single sequence)
//   is aligned to the ground truth by Horn's method; pass 2 is moved by pass 1's
//   alignment and not re-aligned, so it is scored in the frame of the map it localized
//   on (the paper's Table III; `segslam run` does the same).
// - RPE per second (evaluate_rpe.py --fixed_delta --delta 1 --delta_unit s), translation
//   in metres and rotation in degrees; absent when the sequence is shorter than the
//   delta (the reason is kept).
// - Pass 2 only: the map-relative relocalization error, each pass-2 pose against pass 1's
//   estimate at the nearest pass-1 place (harness/map_relative_error.h). Unlike the ATE
//   in the map frame it does not include pass 1's own error: it isolates relocalization.
// - The share of frames localized, from frames.jsonl: tracked, and on a pass run on a
//   loaded map, matched to that map (slam::FrameResult::localized_on_map()); a frame
//   tracked only on the points the run made itself does not count.
// - Raw vs refined mAP, AP50 and mIoU, from seg.json where the run wrote one (mutual
//   loop with a segmenter on a sequence with ground-truth masks).
// - Moving-object detection against the ground-truth tracks (tracks.json), see
//   MovingDetectionScores.
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "harness/map_relative_error.h"
#include "harness/trajectory_metrics.h"

namespace segslam::harness {

// Moving-object detection, counted over instance judgements: every (frame, instance)
// that SLAM judged (frames.jsonl: "judged": true, i.e. it had enough measured points to
// decide) is one sample; its prediction is frames.jsonl's "moving", its truth the
// `moving` flag in tracks.json of the ground-truth instance at that frame. Which
// ground-truth instance that is depends on the masks SLAM saw (trajectory.txt's header):
// - the dataset's masks ("gt"): the same id;
// - a segmenter's masks refined in the mutual loop: the ground-truth id (background
//   included) with the most pixels inside the instance's region of the refined mask SLAM
//   judged (refined_masks/<stem>.png against the dataset's masks/<stem>.png), since a
//   segmenter's ids carry no ground-truth identity;
// - a segmenter's masks that were not saved: not scored (absent, with the reason).
// A ground-truth instance without a tracks.json sample at that frame, and background,
// count as not moving. Instances SLAM did not judge are not counted in precision and
// recall: they are neither detections nor misses there. Coverage counts them: of the
// (frame, truly moving ground-truth instance) pairs SLAM saw (at least one feature on
// the instance, judged or not), the share where it judged the instance moving.
struct MovingDetectionCounts {
  int true_positives = 0;   // judged moving, truly moving
  int false_positives = 0;  // judged moving, truly static
  int false_negatives = 0;  // judged static, truly moving
  int true_negatives = 0;   // judged static, truly static
  int Judged() const { return true_positives + false_positives + false_negatives + true_negatives; }
  double Precision() const;  // tp / (tp + fp); NaN when nothing was judged moving
  double Recall() const;     // tp / (tp + fn); NaN when nothing judged was truly moving
  int moving_seen = 0;           // (frame, truly moving instance) pairs with a feature on it
  int moving_seen_detected = 0;  // of those, judged moving
  double Coverage() const;       // moving_seen_detected / moving_seen; NaN when none was seen
};

// Where the judgement misses: the counts above per band of distance from the camera to
// the object (its tracks.json pose against the frame's ground-truth camera position) and
// per class (instances.json's category), so a user sees which objects it misses.
inline const std::vector<std::string>& MovingDistanceBands() {
  static const std::vector<std::string> bands = {"0_10m", "10_20m", "20_40m", "40m_plus"};
  return bands;
}
inline const std::vector<std::string>& MovingClasses() {
  static const std::vector<std::string> classes = {"person", "car", "truck", "bus", "other"};
  return classes;
}

struct MovingDetectionScores : MovingDetectionCounts {
  std::map<std::string, MovingDetectionCounts> by_distance;  // MovingDistanceBands()
  std::map<std::string, MovingDetectionCounts> by_class;     // MovingClasses()
  // How much of what SLAM saw moved: per frame, the share of the frame's features that lie
  // on truly moving instances (of the masks SLAM used, related to the ground truth as
  // above; exact with the dataset's masks), over every frame with features. Only mutual
  // runs list the instances of a frame, so other modes leave it absent.
  std::optional<ErrorStatistics> moving_feature_share;
};

// mAP, AP50 and mIoU of a set of masks (NaN where seg.json holds null).
struct MaskScores {
  double mAP = 0, AP50 = 0, mIoU = 0;
};

struct PassEvaluation {
  std::string name;                    // "pass1", "pass2" or the sequence folder's name
  std::filesystem::path run_dir;       // where trajectory.txt and frames.jsonl are
  std::filesystem::path sequence_dir;  // the dataset's sequence
  std::string mode;                    // from trajectory.txt's header; "" if not written there
  int frames = 0;                      // frames the run processed
  int localized_frames = 0;
  double LocalizedShare() const { return frames > 0 ? double(localized_frames) / frames : 0.0; }

  // ATE; absent (with the reason) when fewer poses than needed were estimated.
  std::optional<ErrorStatistics> ate_m;
  bool ate_aligned = true;  // false: scored in pass 1's aligned frame
  // The transform applied to the estimate before scoring: Horn's, or pass 1's.
  Eigen::Isometry3d T_gt_est = Eigen::Isometry3d::Identity();
  std::string ate_missing_reason;

  std::optional<ErrorStatistics> rpe_translation_m;    // per second
  std::optional<ErrorStatistics> rpe_rotation_deg;     // per second
  std::string rpe_missing_reason;

  // Pass 2 of a two-pass run only (absent elsewhere): against pass 1's estimate at the
  // same place (harness/map_relative_error.h).
  std::optional<MapRelativeResult> map_relative;

  std::optional<MaskScores> seg_raw, seg_refined;      // from seg.json
  std::string segmenter;                               // seg.json's segmenter

  // Absent when the sequence has no tracks.json (a real TUM sequence), or when the run's
  // instance ids cannot be related to the ground truth (moving_missing_reason).
  std::optional<MovingDetectionScores> moving;
  std::string moving_missing_reason;
  std::string masks;  // trajectory.txt's "instance masks:" line; "" in older runs

  nlohmann::json ToJson() const;
};

struct RunEvaluation {
  std::filesystem::path run_dir;
  std::filesystem::path dataset;
  std::vector<PassEvaluation> passes;

  nlohmann::json ToJson() const;
  // A readable table of every pass (ATE, RPE, localization, map-relative relocalization
  // error, segmentation, moving objects).
  std::string Table() const;
};

// Evaluates the run output `run_dir` (of `segslam run`, single sequence or pass1/pass2
// subfolders) against `dataset`. Throws segslam::Error, message starting "eval: " and
// naming the path, when the dataset has no ground truth, the run has no trajectory or
// frame log, their layouts differ (two passes vs one sequence), or the run's frames are
// not frames of the dataset (a run of another sequence).
RunEvaluation EvaluateRun(const std::filesystem::path& run_dir, const std::filesystem::path& dataset);

// Flat, named metrics of one pass, for thresholds and tables over repeats. Names (units
// in the name; shares and scores in [0, 1]):
//   ate_rmse_m ate_mean_m ate_median_m ate_std_m ate_min_m ate_max_m
//   rpe_trans_rmse_m rpe_rot_rmse_deg          (per second)
//   localized_share
//   reloc_trans_rmse_m reloc_rot_rmse_deg reloc_within_share
//                                              (pass 2 only, map-relative: MapRelativeResult;
//                                               rmse over frames with a place and a pose,
//                                               within share over frames with a place, a
//                                               frame without a pose counting as not within)
//   seg_raw_map seg_raw_ap50 seg_raw_miou seg_refined_map seg_refined_ap50 seg_refined_miou
//   moving_precision moving_recall moving_coverage
//   moving_feature_share_mean moving_feature_share_max   (MovingDetectionScores)
// A metric the pass lacks (no ATE, no seg.json ...) is NaN.
std::map<std::string, double> PassMetrics(const PassEvaluation& pass);
// The names PassMetrics returns, in the order above.
const std::vector<std::string>& PassMetricNames();

}  // namespace segslam::harness
