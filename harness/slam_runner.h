// Runs the SLAM core (slam/tracker.h) over one TUM-layout sequence in one of the three
// modes, with instance masks from the dataset's ground truth or from an external
// segmenter's folder, and writes what a run produces: the trajectory (TUM, camera-to-
// world, localized frames only), one JSON line per frame (status, timings, instance
// judgements) and, on request, the long-term map with a PLY copy.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "core/tum_dataset.h"
#include "slam/map_file.h"
#include "slam/tracker.h"

namespace segslam::harness {

struct SlamRunOptions {
  slam::SlamMode mode = slam::SlamMode::kPlain;
  // "gt": <sequence>/masks/<stem>.png with <sequence>/instances.json; otherwise a folder
  // of external masks (seg/external_masks.h). Unused in plain mode.
  std::string masks = "gt";
  std::filesystem::path map_in;  // a long-term map to localize on (the second pass)
  slam::TrackerOptions tracker;
  int max_frames = 0;            // 0 = all
  // Called after each frame with (done, total); may throw to cancel.
  std::function<void(int, int)> on_frame;
};

struct SlamRunResult {
  std::vector<slam::FrameResult> frames;
  std::vector<StampedPose> trajectory;  // T_wc of the localized frames
  slam::LongTermMapData long_term_map;
  int keyframes = 0;
  int map_points = 0;                   // good points of the tracking map at the end
  double LocalizedShare() const;
  double MedianTrackingMs() const;
};

// Throws segslam::Error naming the file on unreadable frames, masks or map files.
SlamRunResult RunSlamOnSequence(const TumSequence& sequence, const SlamRunOptions& options);

// frames.jsonl: one JSON object per frame.
void WriteFrameLog(const std::filesystem::path& path, const std::vector<slam::FrameResult>& frames);

}  // namespace segslam::harness
