// A frame's calls to slam::Tracker in the order the frame pipeline makes them
// (mutual/frame_pipeline.h, which is where a mode chooses its steps), for the tests of
// slam/ on its own.
#pragma once

#include <cstdint>
#include <unordered_set>

#include "core/frame.h"
#include "slam/tracker.h"

namespace segslam::slam {

// Every feature, no masks (the plain baseline).
inline FrameResult TrackPlain(Tracker& tracker, const RgbdFrame& frame) {
  tracker.BeginFrame(frame);
  tracker.EstimateCoarsePose();
  tracker.EstimateFinePose();
  return tracker.UpdateMaps();
}

// Features on moveable-class instances dropped before tracking (mask-moveable).
inline FrameResult TrackMaskMoveable(Tracker& tracker, const RgbdFrame& frame, const FrameInstances& instances) {
  tracker.BeginFrame(frame);
  tracker.DropMoveableFeatures(instances);
  tracker.EstimateCoarsePose();
  tracker.EstimateFinePose();
  return tracker.UpdateMaps();
}

// Instances judged moving or static between the coarse and the fine pose (mutual), or
// given their verdicts (the oracle).
inline FrameResult TrackJudging(Tracker& tracker, const RgbdFrame& frame, const FrameInstances& instances,
                                const std::unordered_set<std::uint16_t>* given_moving_ids = nullptr) {
  tracker.BeginFrame(frame);
  tracker.EstimateCoarsePose();
  tracker.JudgeInstances(instances, given_moving_ids);
  tracker.EstimateFinePose();
  return tracker.UpdateMaps();
}

}  // namespace segslam::slam
