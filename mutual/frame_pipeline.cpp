#include "mutual/frame_pipeline.h"

#include <chrono>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "core/coco.h"
#include "core/error.h"

namespace segslam::mutual {
namespace {

double MillisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// The tracker's options as the mode has them: mutual-sparse judges as the paper does.
slam::TrackerOptions TrackerOptionsFor(const FramePipelineOptions& options) {
  slam::TrackerOptions tracker = options.tracker;
  if (options.mode == SlamMode::kMutualSparse) tracker.judge_by_depth = false;
  return tracker;
}

}  // namespace

slam::FrameInstances ToFrameInstances(const seg::FrameSegmentation& segmentation, cv::Size size) {
  slam::FrameInstances instances;
  instances.ids = segmentation.ToIdImage(size);
  for (const seg::InstanceMask& instance : segmentation.instances) {
    if (IsMoveableCategory(instance.category_id)) instances.moveable_ids.insert(instance.track_id);
  }
  return instances;
}

FramePipeline::FramePipeline(const PinholeCamera& camera, const FramePipelineOptions& options,
                             seg::Segmenter* segmenter, const seg::GroundTruthMotion* motion)
    : camera_(camera),
      options_(options),
      segmenter_(segmenter),
      motion_(motion),
      tracker_(std::make_unique<slam::Tracker>(camera, TrackerOptionsFor(options))),
      refiner_(options.refiner) {
  const std::string mode = ToString(options.mode);
  if (UsesMasks(options.mode) && segmenter == nullptr) throw Error("mode " + mode + " needs instance masks");
  if (options.mode == SlamMode::kOracle && motion == nullptr) {
    throw Error("mode oracle needs the ground truth's moving instances");
  }
  std::string error;
  if (RefinesMasks() && !options.refiner.IsValid(&error)) throw Error("mutual loop: refiner options: " + error);
  // The oracle knows every verdict from the first frame; plain and mask-moveable judge nothing.
  at_start_ = options.tracker.retrack_map_start && JudgesInstances(options.mode) && options.mode != SlamMode::kOracle;
}

void FramePipeline::LoadLongTermMap(const slam::LongTermMapData& map, const std::string& origin) {
  tracker_->LoadLongTermMap(map, origin);
  long_term_map_origin_ = origin;
}

FrameStep FramePipeline::ProcessFrame(const RgbdFrame& frame) {
  FrameStep step;
  const SlamMode mode = options_.mode;
  const cv::Size size = frame.color_bgr.size();
  // 1. The segmenter's instances.
  if (UsesMasks(mode)) {
    const auto segment_start = std::chrono::steady_clock::now();
    step.initial = segmenter_->Segment(frame);
    step.initial.frame_index = frame.index;
    step.segment_ms = MillisecondsSince(segment_start);
  }
  tracker_->BeginFrame(frame);
  if (mode == SlamMode::kMaskMoveable) tracker_->DropMoveableFeatures(ToFrameInstances(step.initial, size));

  // 2. Coarse pose from every feature left.
  const std::optional<Eigen::Isometry3d> T_wc_coarse = tracker_->EstimateCoarsePose();

  // 3. The refinement, with the coarse pose.
  if (RefinesMasks()) {
    Refine(frame, T_wc_coarse, &step);
  } else {
    step.refined = step.initial;
  }

  // 4. Moving/static judgement on the refined instances, fine pose, maps.
  slam::FrameInstances instances;
  if (JudgesInstances(mode)) {
    instances = ToFrameInstances(step.refined, size);
    if (mode == SlamMode::kOracle) {
      tracker_->JudgeInstances(instances, &motion_->MovingIds(frame.index));
    } else {
      tracker_->JudgeInstances(instances);
    }
  }
  tracker_->EstimateFinePose();
  step.slam = tracker_->UpdateMaps();
  Record(step.slam);
  if (at_start_) RememberMapStart(frame, instances, &step);

  // 5. What frame t+1's refinement needs.
  if (RefinesMasks()) {
    previous_refined_ = step.refined;
    previous_depth_m_ = frame.depth_m.clone();  // the caller may reuse the frame's buffers
    previous_T_wc_fine_.reset();
    if (step.slam.localized()) previous_T_wc_fine_ = step.slam.T_wc;
  }
  return step;
}

void FramePipeline::RememberMapStart(const RgbdFrame& frame, const slam::FrameInstances& instances,
                                     FrameStep* step) {
  StartFrame kept;
  kept.frame = frame;
  kept.frame.color_bgr = frame.color_bgr.clone();  // the caller may reuse the frame's buffers
  kept.frame.depth_m = frame.depth_m.clone();
  kept.instances = instances;  // made for this frame (ToFrameInstances), shared with no one
  start_frames_.push_back(std::move(kept));
  if (frame.stamp_s - start_frames_.front().frame.stamp_s < options_.tracker.motion_baseline_s - 1e-6) return;
  at_start_ = false;
  if (StartWorthRetracking()) RetrackMapStart(step);
  start_frames_ = {};
}

// Only a still verdict changes what the start would have been: an instance judged moving
// was kept out all the same while it waited. A start with a lost frame is left as it was:
// its map did not begin on the pass's first frame, or the pass began off the loaded map.
bool FramePipeline::StartWorthRetracking() const {
  for (const slam::FrameResult& result : frames_) {
    if (!result.localized() || result.map_reset) return false;
  }
  std::unordered_set<std::uint16_t> kept_out_unjudged;
  for (size_t k = 0; k + 1 < frames_.size(); ++k) {
    for (const slam::InstanceJudgement& judgement : frames_[k].instances) {
      if (judgement.moveable_class && !judgement.judged) kept_out_unjudged.insert(judgement.id);
    }
  }
  for (const slam::InstanceJudgement& judgement : frames_.back().instances) {
    if (judgement.judged && !judgement.moving && kept_out_unjudged.count(judgement.id) > 0) return true;
  }
  return false;
}

void FramePipeline::RetrackMapStart(FrameStep* step) {
  auto retracked = std::make_unique<slam::Tracker>(camera_, TrackerOptionsFor(options_));
  if (tracker_->localization_mode()) {
    retracked->LoadLongTermMap(tracker_->ExportLongTermMap(/*include_instances=*/false), long_term_map_origin_);
  }
  std::unordered_map<std::uint16_t, bool> moving_by_id;
  for (const slam::InstanceJudgement& judgement : frames_.back().instances) {
    if (judgement.judged) moving_by_id[judgement.id] = judgement.moving;
  }
  // The last frame of the start judges on its own evidence again.
  retracked->PresetStartVerdicts(std::move(moving_by_id), start_frames_.back().frame.stamp_s);
  const std::vector<slam::FrameResult> first_tries = std::move(frames_);
  frames_.clear();
  trajectory_.clear();
  for (size_t k = 0; k < start_frames_.size(); ++k) {
    const StartFrame& kept = start_frames_[k];
    retracked->BeginFrame(kept.frame);
    retracked->EstimateCoarsePose();
    retracked->JudgeInstances(kept.instances);
    retracked->EstimateFinePose();
    slam::FrameResult result = retracked->UpdateMaps();
    result.retracked = true;
    // The frame was tracked twice, and its time is both.
    const slam::FrameTimings& first = first_tries[k].timings;
    result.timings.features_ms += first.features_ms;
    result.timings.coarse_ms += first.coarse_ms;
    result.timings.judge_ms += first.judge_ms;
    result.timings.fine_ms += first.fine_ms;
    result.timings.map_update_ms += first.map_update_ms;
    result.timings.bundle_adjustment_ms += first.bundle_adjustment_ms;
    Record(result);
  }
  tracker_ = std::move(retracked);
  step->slam = frames_.back();
}

void FramePipeline::Refine(const RgbdFrame& frame, const std::optional<Eigen::Isometry3d>& T_wc_coarse,
                           FrameStep* step) {
  const auto refine_start = std::chrono::steady_clock::now();
  seg::RefinerInput input;
  input.current_initial = step->initial;
  input.camera = camera_;
  // No projection without both poses in one frame; Refine then returns the initial
  // regions with fresh ids, as on the first frame.
  const bool can_project = previous_refined_.has_value() && previous_T_wc_fine_.has_value() &&
                           T_wc_coarse.has_value() && !tracker_->CoarsePoseRelocalized() &&
                           !previous_depth_m_.empty();
  if (can_project) {
    input.previous_refined = &*previous_refined_;
    input.previous_depth_m = previous_depth_m_;
    input.current_depth_m = frame.depth_m;
    input.T_wc_previous_fine = *previous_T_wc_fine_;
    input.T_wc_current_coarse = *T_wc_coarse;
  }
  seg::RefinementResult refinement = refiner_.Refine(input);
  step->refine_ms = MillisecondsSince(refine_start);
  step->refined_in_loop = true;
  step->refined_from_previous = can_project;
  step->refined = std::move(refinement.refined);
  step->refined.frame_index = frame.index;
  step->decisions = std::move(refinement.decisions);
}

void FramePipeline::Record(const slam::FrameResult& frame) {
  if (frame.map_reset) {
    for (slam::FrameResult& earlier : frames_) earlier.status = slam::TrackingStatus::kLost;
    trajectory_.clear();
  }
  if (frame.localized()) trajectory_.push_back({frame.stamp_s, frame.T_wc});
  frames_.push_back(frame);
}

slam::LongTermMapData FramePipeline::ExportLongTermMap() const {
  return tracker_->ExportLongTermMap(/*include_instances=*/!JudgesInstances(options_.mode));
}

}  // namespace segslam::mutual
