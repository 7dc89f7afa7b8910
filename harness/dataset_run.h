// Runs the SLAM core over a dataset the way `segslam run` does and writes its outputs:
// a single TUM-layout sequence, or both passes of a generated dataset (pass 1 builds the
// long-term map, pass 2 localizes on it: the paper's relocalization protocol). Shared by
// `segslam run` and `segslam scenario run`, so both leave the same layout behind:
//   OUT/run.json                 what the run read (SequenceIdentity per pass), its mode
//   OUT/[passN/]trajectory.txt   TUM, camera-to-world T_wc of the localized frames
//   OUT/[passN/]frames.jsonl     one JSON line per frame (harness/slam_runner.h)
//   OUT/[passN/]seg.json         raw vs refined masks (mutual loop with ground-truth masks)
//   OUT/[passN/]refined_masks/   the loop's refined masks
//   OUT/pass1/map.segslam (+ .ply)  the long-term map of pass 1
// OUT is one unit: staged beside its place and renamed there only when complete, with
// the map (core/atomic_file.h's StagingDirectory).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "harness/run_config.h"
#include "harness/slam_runner.h"
#include "harness/trajectory_metrics.h"

namespace segslam::harness {

struct DatasetRunOptions {
  RunConfig run;                  // the mode and its masks, checked (MakeRunConfig)
  std::filesystem::path map_in;   // single sequence only: localize on this map
  std::filesystem::path map_out;  // where the (pass-1) long-term map goes; empty = default
  std::string camera_file;        // camera.yaml overriding the sequence's own
  int frames = 0;                 // first N frames of each sequence (0 = all)
  // NAME=VALUE overrides of slam::TrackerOptions (slam/tracker_options.h).
  std::vector<std::string> tracker_options;
  // NAME=VALUE overrides of the mutual loop's seg::RefinerOptions
  // (seg/refiner_options.h); only where the loop runs (RunConfig::RefinesMasks).
  std::vector<std::string> refiner_options;
  // Called after each frame with the pass's name, (done, total); may throw to cancel.
  std::function<void(const std::string&, int, int)> on_frame;
};

// One sequence's run. `ate` is set where the sequence has ground truth and >= 3 poses
// were estimated: pass 1 (or a single sequence) aligned by Horn's method, pass 2 moved by
// pass 1's alignment and not re-aligned (scored in the map's frame, the paper's Table III).
// What tells a sequence from another with the same frame stamps (two generated worlds of
// one frame rate): its first colour file and that file's SHA-256, as a folder of masks
// records them (seg/external_masks.h).
struct SequenceIdentity {
  std::filesystem::path sequence_dir;
  std::string first_frame;  // relative to sequence_dir, e.g. "rgb/0.000000.png"
  std::string first_frame_sha256;
};

struct PassRun {
  std::string name;  // "pass1", "pass2", or the sequence folder's name
  SequenceIdentity sequence;  // what the pass read
  SlamRunResult run;
  std::optional<AteResult> ate;
  bool aligned = true;
};

// True when `dataset` holds pass1/ and pass2/.
bool IsTwoPassDataset(const std::filesystem::path& dataset);

// The SLAM runner's options for a sequence of a run with `options`: mode, masks, frames,
// and the tracker's and (where the mutual loop runs) the refiner's overrides. What is a
// pass's own (map_in, refined_masks_dir, on_frame) the caller adds. Throws
// segslam::Error on a bad override.
SlamRunOptions SlamRunOptionsFor(const DatasetRunOptions& options);

// Throws segslam::Error on bad options (an unknown tracker option, refiner options where
// no loop runs or out of range), so a command can refuse them before it prints or reads
// anything. The mode and masks were checked when `options.run` was made.
void CheckDatasetRunOptions(const DatasetRunOptions& options);

// Runs every pass and writes the outputs above under `out_dir`, replacing an earlier run
// output there. Throws segslam::Error, before anything is written, on bad options
// (CheckDatasetRunOptions, and --map-in on a two-pass dataset), an `out_dir` that is a file
// or a folder holding what a run does not write (core/output_folders.h), a map_out that
// is a folder; and on unreadable input naming the file, leaving `out_dir` and map_out as
// they were.
std::vector<PassRun> RunDataset(const std::filesystem::path& dataset, const std::filesystem::path& out_dir,
                                const DatasetRunOptions& options);

// Throws segslam::Error, message starting "eval: " and naming both sequences, when the
// run.json of the pass folder `pass_dir` (OUT, or OUT/pass1 with OUT/run.json) records a
// first colour frame that `sequence_dir` lacks or holds with other bytes: a run of another
// sequence. A run without run.json (from an older build) is not checked here.
void CheckRunReadSequence(const std::filesystem::path& pass_dir, const std::filesystem::path& sequence_dir);

}  // namespace segslam::harness
