#include "mutual/frame_pipeline.h"

#include <chrono>
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
      tracker_(camera, TrackerOptionsFor(options)),
      refiner_(options.refiner) {
  const std::string mode = ToString(options.mode);
  if (UsesMasks(options.mode) && segmenter == nullptr) throw Error("mode " + mode + " needs instance masks");
  if (options.mode == SlamMode::kOracle && motion == nullptr) {
    throw Error("mode oracle needs the ground truth's moving instances");
  }
  std::string error;
  if (RefinesMasks() && !options.refiner.IsValid(&error)) throw Error("mutual loop: refiner options: " + error);
}

void FramePipeline::LoadLongTermMap(const slam::LongTermMapData& map, const std::string& origin) {
  tracker_.LoadLongTermMap(map, origin);
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
  tracker_.BeginFrame(frame);
  if (mode == SlamMode::kMaskMoveable) tracker_.DropMoveableFeatures(ToFrameInstances(step.initial, size));

  // 2. Coarse pose from every feature left.
  const std::optional<Eigen::Isometry3d> T_wc_coarse = tracker_.EstimateCoarsePose();

  // 3. The refinement, with the coarse pose.
  if (RefinesMasks()) {
    Refine(frame, T_wc_coarse, &step);
  } else {
    step.refined = step.initial;
  }

  // 4. Moving/static judgement on the refined instances, fine pose, maps.
  if (JudgesInstances(mode)) {
    const slam::FrameInstances instances = ToFrameInstances(step.refined, size);
    if (mode == SlamMode::kOracle) {
      tracker_.JudgeInstances(instances, &motion_->MovingIds(frame.index));
    } else {
      tracker_.JudgeInstances(instances);
    }
  }
  tracker_.EstimateFinePose();
  step.slam = tracker_.UpdateMaps();
  Record(step.slam);

  // 5. What frame t+1's refinement needs.
  if (RefinesMasks()) {
    previous_refined_ = step.refined;
    previous_depth_m_ = frame.depth_m.clone();  // the caller may reuse the frame's buffers
    previous_T_wc_fine_.reset();
    if (step.slam.localized()) previous_T_wc_fine_ = step.slam.T_wc;
  }
  return step;
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
                           T_wc_coarse.has_value() && !tracker_.CoarsePoseRelocalized() &&
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
  return tracker_.ExportLongTermMap(/*include_instances=*/!JudgesInstances(options_.mode));
}

}  // namespace segslam::mutual
