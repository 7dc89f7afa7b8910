#include "harness/dataset_run.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "seg/refiner_option_overrides.h"
#include "slam/tracker_option_overrides.h"

namespace segslam::harness {

namespace fs = std::filesystem;

std::string SimulatedSegmenterLabel(const std::string& preset, double strength) {
  return strength == 1.0 ? preset : fmt::format("{}@{}", preset, strength);
}

namespace {

// `fixed_alignment`: score the ATE in that frame (pass 2 in pass 1's map frame); without
// one, align (Horn), unless `in_map_frame` says there is no map frame to score in.
PassRun RunPass(const DatasetRunOptions& args, const std::string& name, const fs::path& sequence_dir,
                const fs::path& map_in, const fs::path& map_out, const fs::path& out_dir,
                const std::optional<Eigen::Isometry3d>& fixed_alignment, bool in_map_frame = false) {
  const TumSequence sequence = TumSequence::OpenWithCameraFile(sequence_dir, args.camera_file);
  // What an earlier run of another kind left here would be read as this run's.
  for (const char* stale : {"seg.json", "refined_masks"}) fs::remove_all(out_dir / stale);
  SlamRunOptions options;
  options.mode = slam::ParseSlamMode(args.mode);
  options.masks = args.masks;
  options.segmenter = args.segmenter;
  options.segmenter_seed = args.seed;
  options.segmenter_strength = args.strength;
  if (RunsMutualLoop(args)) options.refined_masks_dir = out_dir / "refined_masks";
  options.map_in = map_in;
  options.max_frames = args.frames;
  for (const std::string& assignment : args.tracker_options) slam::SetTrackerOption(&options.tracker, assignment);
  for (const std::string& assignment : args.refiner_options) seg::SetRefinerOption(&options.refiner, assignment);
  options.on_frame = [&](int done, int total) {
    if (args.on_frame) args.on_frame(name, done, total);
  };
  PassRun outcome;
  outcome.name = name;
  outcome.aligned = !fixed_alignment.has_value() && !in_map_frame;
  outcome.run = RunSlamOnSequence(sequence, options);

  fs::create_directories(out_dir);
  // The header says which masks gave the instance ids of frames.jsonl (eval needs it).
  const std::string simulated =
      fmt::format("simulated {} seed {}", SimulatedSegmenterLabel(args.segmenter, args.strength), args.seed);
  const std::string masks = args.mode == "plain"       ? "none"
                            : !args.segmenter.empty()  ? simulated
                            : args.masks == "gt"       ? "gt"
                                                       : "external " + args.masks;
  WriteTumTrajectory(out_dir / "trajectory.txt", outcome.run.trajectory,
                     fmt::format("segslam run, mode {}, sequence {}\ninstance masks: {}\ncamera-to-world T_wc of "
                                 "localized frames",
                                 args.mode, sequence_dir.string(), masks));
  WriteFrameLog(out_dir / "frames.jsonl", outcome.run.frames);
  if (outcome.run.segmentation.has_value()) {
    const LoopSegmentationScores& scores = *outcome.run.segmentation;
    const nlohmann::json json = {
        {"sequence", sequence_dir.string()},
        {"segmenter", scores.segmenter},
        {"seed", args.seed},
        {"poses", "slam"},
        {"frames", outcome.run.frames.size()},
        {"refined_from_previous_frames", scores.refined_from_previous},
        {"raw", scores.raw.ToJson()},
        {"refined", scores.refined.ToJson()},
        {"refine_ms_median", scores.refine_ms_median},
        {"decisions",
         {{"new", scores.decision_counts[0]},
          {"kept", scores.decision_counts[1]},
          {"replaced", scores.decision_counts[2]},
          {"added", scores.decision_counts[3]},
          {"dropped", scores.decision_counts[4]}}}};
    WriteFileAtomically(out_dir / "seg.json", json.dump(2) + "\n");
  }
  if (!map_out.empty()) {
    slam::SaveLongTermMap(map_out, outcome.run.long_term_map);
    fs::path ply = map_out;
    ply.replace_extension(".ply");
    slam::ExportPly(ply, outcome.run.long_term_map);
  }
  if (sequence.has_groundtruth() && outcome.run.trajectory.size() >= 3 && !(in_map_frame && !fixed_alignment)) {
    AteOptions ate_options;
    std::vector<StampedPose> estimate = outcome.run.trajectory;
    if (fixed_alignment.has_value()) {
      ate_options.align = false;
      for (StampedPose& pose : estimate) pose.T_wc = *fixed_alignment * pose.T_wc;
    }
    outcome.ate = ComputeAte(sequence.groundtruth(), estimate, ate_options);
  }
  return outcome;
}

}  // namespace

bool IsTwoPassDataset(const fs::path& dataset) {
  return fs::is_directory(dataset / "pass1") && fs::is_directory(dataset / "pass2");
}

bool RunsMutualLoop(const DatasetRunOptions& options) {
  return options.mode == "mutual" && (!options.segmenter.empty() || options.masks != "gt");
}

void CheckDatasetRunOptions(const DatasetRunOptions& options) {
  slam::ParseSlamMode(options.mode);
  slam::TrackerOptions tracker;
  for (const std::string& assignment : options.tracker_options) slam::SetTrackerOption(&tracker, assignment);
  if (!options.segmenter.empty() && options.masks != "gt") {
    throw Error("run: --segmenter " + options.segmenter + " and --masks " + options.masks + " exclude each other");
  }
  if (options.mode == "oracle" && (!options.segmenter.empty() || options.masks != "gt")) {
    throw Error("run: mode oracle takes the dataset's ground-truth masks and tracks (the verdicts a perfect "
                "judgement would give): no --segmenter or --masks DIR");
  }
  if (!options.refiner_options.empty()) {
    if (!RunsMutualLoop(options)) {
      throw Error("run: --refiner applies to the mutual loop: mode mutual with --segmenter or --masks");
    }
    seg::RefinerOptions refiner;
    for (const std::string& assignment : options.refiner_options) seg::SetRefinerOption(&refiner, assignment);
    if (std::string problem; !refiner.IsValid(&problem)) throw Error("run: --refiner: " + problem);
  }
}

std::vector<PassRun> RunDataset(const fs::path& dataset, const fs::path& out_dir, const DatasetRunOptions& options) {
  CheckDatasetRunOptions(options);
  std::vector<PassRun> passes;
  if (IsTwoPassDataset(dataset)) {
    if (!options.map_in.empty()) {
      throw Error("run: --map-in applies to a single sequence; " + dataset.string() + " has two passes");
    }
    const fs::path map1 = options.map_out.empty() ? out_dir / "pass1" / "map.segslam" : options.map_out;
    fs::create_directories(map1.parent_path().empty() ? fs::path(".") : map1.parent_path());
    passes.push_back(RunPass(options, "pass1", dataset / "pass1", {}, map1, out_dir / "pass1", std::nullopt));
    // Pass 2 is scored in the map's frame: pass 1's alignment to the ground truth, not
    // a new one (the paper's Table III); without it, not at all.
    std::optional<Eigen::Isometry3d> alignment;
    if (passes[0].ate.has_value()) alignment = passes[0].ate->T_gt_est;
    passes.push_back(RunPass(options, "pass2", dataset / "pass2", map1, {}, out_dir / "pass2", alignment,
                             /*in_map_frame=*/true));
  } else {
    passes.push_back(RunPass(options, dataset.filename().string(), dataset, options.map_in, options.map_out, out_dir,
                             std::nullopt));
  }
  return passes;
}

}  // namespace segslam::harness
