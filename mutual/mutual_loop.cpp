#include "mutual/mutual_loop.h"

#include <chrono>
#include <utility>

#include "core/coco.h"
#include "core/error.h"

namespace segslam::mutual {
namespace {

double MillisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
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

MutualLoop::MutualLoop(const PinholeCamera& camera, seg::Segmenter& segmenter, const MutualLoopOptions& options)
    : camera_(camera),
      segmenter_(segmenter),
      options_(options),
      tracker_(camera, options.tracker),
      refiner_(options.refiner) {
  std::string error;
  if (!options.refiner.IsValid(&error)) throw Error("mutual loop: refiner options: " + error);
}

void MutualLoop::LoadLongTermMap(const slam::LongTermMapData& map, const std::string& origin) {
  tracker_.LoadLongTermMap(map, origin);
}

MutualFrameResult MutualLoop::ProcessFrame(const RgbdFrame& frame) {
  MutualFrameResult result;
  const auto segment_start = std::chrono::steady_clock::now();
  result.initial = segmenter_.Segment(frame);
  result.initial.frame_index = frame.index;
  result.segment_ms = MillisecondsSince(segment_start);

  tracker_.BeginFrame(frame);
  const std::optional<Eigen::Isometry3d> T_wc_coarse = tracker_.EstimateCoarsePose();

  const auto refine_start = std::chrono::steady_clock::now();
  seg::RefinerInput input;
  input.current_initial = result.initial;
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
  result.refine_ms = MillisecondsSince(refine_start);
  result.refined_from_previous = can_project;
  result.refined = std::move(refinement.refined);
  result.refined.frame_index = frame.index;
  result.decisions = std::move(refinement.decisions);

  tracker_.JudgeInstances(ToFrameInstances(result.refined, frame.color_bgr.size()));
  tracker_.EstimateFinePose();
  result.slam = tracker_.UpdateMaps();

  previous_refined_ = result.refined;
  previous_depth_m_ = frame.depth_m.clone();  // the caller may reuse the frame's buffers
  previous_T_wc_fine_.reset();
  if (result.slam.localized()) previous_T_wc_fine_ = result.slam.T_wc;
  return result;
}

}  // namespace segslam::mutual
