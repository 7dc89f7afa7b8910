// Runs the frame pipeline (mutual/frame_pipeline.h) over one TUM-layout sequence in one
// of the modes, with instance masks from the dataset's ground truth, from an external
// segmenter's folder or from the simulated segmenter, and collects what a run produces:
// the trajectory (TUM, camera-to-world, localized frames only), each frame's result
// (status, timings, instance judgements; written as frames.jsonl) and the long-term map.
//
// Where the mutual loop refines masks (mutual mode with a segmenter or external masks)
// the refined masks can be written out, and on a sequence with ground-truth masks raw
// and refined masks are scored (seg/metrics.h).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "core/tum_dataset.h"
#include "mutual/frame_pipeline.h"
#include "harness/run_config.h"
#include "mutual/slam_mode.h"
#include "seg/metrics.h"
#include "slam/map_file.h"
#include "slam/tracker.h"

namespace segslam::harness {

struct SlamRunOptions {
  // The mode and its masks (harness/run_config.h); plain by default. The oracle also reads
  // <sequence>/tracks.json for which instances move.
  RunConfig run{mutual::SlamMode::kPlain, MaskSource{}};
  // The loop's refiner options (mutual mode with a segmenter).
  seg::RefinerOptions refiner;
  // Where the loop writes each frame's refined masks, in the external-mask layout
  // (seg/external_masks.h: <stem>.png + <stem>.json); empty = not written.
  std::filesystem::path refined_masks_dir;
  std::filesystem::path map_in;  // a long-term map to localize on (the second pass)
  slam::TrackerOptions tracker;
  int max_frames = 0;            // 0 = all
  // Read and decode the next frame on another thread while one is processed. Off where
  // stage timings on one core are measured (bench slam), so decoding cannot preempt them.
  bool read_ahead = true;
  // Called after each frame with (done, total); may throw to cancel.
  std::function<void(int, int)> on_frame;
};

// Raw vs refined masks of a mutual-loop run against the sequence's ground-truth masks,
// with SLAM's poses ("segmentation in the loop"; seg-eval does the same with the true
// poses).
struct LoopSegmentationScores {
  std::string segmenter;             // the segmenter's name()
  seg::SegmentationScores raw;       // the segmenter's masks
  seg::SegmentationScores refined;   // the loop's refined masks
  int refined_from_previous = 0;     // frames refined by projecting the previous frame
  // RegionDecision kinds summed over the sequence, indexed by RegionDecision::Kind.
  std::array<int, 5> decision_counts{};
  double refine_ms_median = 0;
};

struct SlamRunResult {
  std::vector<slam::FrameResult> frames;
  // Mutual loop on a sequence with ground-truth masks only.
  std::optional<LoopSegmentationScores> segmentation;
  // Per frame, the mutual loop's mask refinement; empty where no loop ran (no segmenter).
  std::vector<double> refine_ms;
  std::vector<StampedPose> trajectory;  // T_wc of the localized frames
  slam::LongTermMapData long_term_map;
  int keyframes = 0;
  int map_points = 0;                   // good points of the tracking map at the end
  double LocalizedShare() const;
  double MedianTrackingMs() const;
};

// Throws segslam::Error naming the file on unreadable frames, masks, tracks or map files,
// and segslam::Error on a mode without the masks it needs (the oracle: the ground truth's).
SlamRunResult RunSlamOnSequence(const TumSequence& sequence, const SlamRunOptions& options);

// frames.jsonl: one JSON object per frame.
void WriteFrameLog(const std::filesystem::path& path, const std::vector<slam::FrameResult>& frames);

}  // namespace segslam::harness
