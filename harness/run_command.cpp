// `segslam run`: the SLAM core over a sequence, or over both passes of a generated
// dataset (pass 1 builds the long-term map, pass 2 localizes on it: the paper's
// relocalization protocol). In mutual mode with a segmenter (--segmenter or --masks DIR)
// it runs the paper's loop, writes the refined masks and, on a sequence with ground-truth
// masks, scores raw vs refined masks with SLAM's poses.
#include <chrono>
#include <cmath>
#include <cstdio>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "harness/commands.h"
#include "harness/interrupt.h"
#include "harness/progress_bar.h"
#include "harness/slam_runner.h"
#include "harness/trajectory_metrics.h"
#include "seg/simulated_segmenter.h"
#include "slam/tracker_option_overrides.h"

namespace segslam::harness {

namespace fs = std::filesystem;

namespace {

struct RunArgs {
  std::string dataset;
  std::string mode = "mutual";
  std::string masks = "gt";
  std::string segmenter;  // a simulated segmenter preset; empty = none
  std::uint64_t seed = 1;
  std::string map_in;
  std::string map_out;
  std::string out_dir;
  std::string camera_file;
  int frames = 0;
  std::vector<std::string> tracker_options;  // NAME=VALUE overrides of slam::TrackerOptions
  bool quiet = false;
};

struct PassOutcome {
  SlamRunResult run;
  std::optional<AteResult> ate;
};

PassOutcome RunPass(const RunArgs& args, const fs::path& sequence_dir, const fs::path& map_in,
                    const fs::path& map_out, const fs::path& out_dir,
                    const std::optional<Eigen::Isometry3d>& fixed_alignment) {
  std::optional<SequenceCamera> camera;
  if (!args.camera_file.empty()) camera = ReadCameraYaml(args.camera_file);
  const TumSequence sequence = TumSequence::Open(sequence_dir, camera);
  SlamRunOptions options;
  options.mode = slam::ParseSlamMode(args.mode);
  options.masks = args.masks;
  options.segmenter = args.segmenter;
  options.segmenter_seed = args.seed;
  const bool mutual_loop = options.mode == slam::SlamMode::kMutual && (!args.segmenter.empty() || args.masks != "gt");
  if (mutual_loop) options.refined_masks_dir = out_dir / "refined_masks";
  options.map_in = map_in;
  options.max_frames = args.frames;
  for (const std::string& assignment : args.tracker_options) slam::SetTrackerOption(&options.tracker, assignment);
  ProgressBar bar(fmt::format("run {} {}", args.mode, sequence_dir.filename().string()));
  const std::atomic<bool>* cancel = InstallInterruptFlag();
  const auto start = std::chrono::steady_clock::now();
  options.on_frame = [&](int done, int total) {
    if (cancel->load()) throw Error("run: cancelled");
    if (args.quiet) return;
    const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    bar.Update(done, total, done / elapsed_s);
  };
  PassOutcome outcome;
  outcome.run = RunSlamOnSequence(sequence, options);
  if (!args.quiet) bar.Finish();

  fs::create_directories(out_dir);
  WriteTumTrajectory(out_dir / "trajectory.txt", outcome.run.trajectory,
                     fmt::format("segslam run, mode {}, sequence {}\ncamera-to-world T_wc of localized frames",
                                 args.mode, sequence_dir.string()));
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
  if (sequence.has_groundtruth() && outcome.run.trajectory.size() >= 3) {
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

void PrintPass(const std::string& name, const PassOutcome& pass, bool aligned) {
  const SlamRunResult& run = pass.run;
  fmt::print("{:<8} {:>6} {:>9.1f}% {:>9} {:>9} {:>10.2f}", name, run.frames.size(), 100 * run.LocalizedShare(),
             run.keyframes, run.map_points, run.MedianTrackingMs());
  if (pass.ate.has_value()) {
    fmt::print(" {:>10.4f} {:>10.4f}  {}\n", pass.ate->translation_m.rmse, pass.ate->translation_m.max, aligned ? "aligned" : "map frame");
  } else {
    fmt::print(" {:>10} {:>10}\n", "n/a", "n/a");
  }
}

std::string Points(double value) { return std::isnan(value) ? "  n/a" : fmt::format("{:5.1f}", 100 * value); }

// The segmentation-in-the-loop table, as seg-eval prints it with ground-truth poses.
void PrintLoopSegmentation(const std::vector<std::pair<std::string, PassOutcome>>& passes) {
  bool header = false;
  for (const auto& [name, pass] : passes) {
    if (!pass.run.segmentation.has_value()) continue;
    const LoopSegmentationScores& s = *pass.run.segmentation;
    if (!header) {
      fmt::print("\nSegmentation in the loop (SLAM poses), segmenter {}\n", s.segmenter);
      fmt::print("{:<8} {:>6} | {:>6} {:>6} {:>6} | {:>6} {:>6} {:>6} | {:>6} {:>6} {:>6}\n", "sequence", "frames",
                 "mAP", "AP50", "mIoU", "mAP", "AP50", "mIoU", "dmAP", "dAP50", "dmIoU");
      fmt::print("{:<8} {:>6} | {:^20} | {:^20} | {:^20}\n", "", "", "raw", "refined", "refined - raw");
      header = true;
    }
    fmt::print("{:<8} {:>6} | {} {} {} | {} {} {} | {} {} {}\n", name, pass.run.frames.size(), Points(s.raw.mAP),
               Points(s.raw.AP50), Points(s.raw.mIoU), Points(s.refined.mAP), Points(s.refined.AP50),
               Points(s.refined.mIoU), Points(s.refined.mAP - s.raw.mAP), Points(s.refined.AP50 - s.raw.AP50),
               Points(s.refined.mIoU - s.raw.mIoU));
  }
  if (header) fmt::print("(points: percent; seg.json and refined_masks/ beside each trajectory)\n");
}

int RunRun(const RunArgs& args) {
  slam::ParseSlamMode(args.mode);  // a bad mode fails before anything is read or written
  slam::TrackerOptions checked;
  for (const std::string& assignment : args.tracker_options) slam::SetTrackerOption(&checked, assignment);
  if (!args.segmenter.empty() && args.masks != "gt") {
    throw Error("run: --segmenter " + args.segmenter + " and --masks " + args.masks + " exclude each other");
  }
  const fs::path dataset(args.dataset);
  const fs::path out_dir = args.out_dir.empty() ? dataset / ("run_" + args.mode) : fs::path(args.out_dir);
  const bool two_pass = fs::is_directory(dataset / "pass1") && fs::is_directory(dataset / "pass2");
  const std::string masks = args.mode == "plain"        ? "none"
                            : !args.segmenter.empty()   ? "simulated " + args.segmenter + fmt::format(" (seed {})", args.seed)
                                                        : args.masks;
  fmt::print("segslam run: mode {}, masks {}{}\n", args.mode, masks,
             args.mode == "mutual" && masks != "gt" ? ", refined in the loop" : "");
  std::vector<std::pair<std::string, PassOutcome>> passes;
  if (two_pass) {
    if (!args.map_in.empty()) throw Error("run: --map-in applies to a single sequence; " + args.dataset + " has two passes");
    const fs::path map1 = args.map_out.empty() ? out_dir / "pass1" / "map.segslam" : fs::path(args.map_out);
    fs::create_directories(map1.parent_path().empty() ? fs::path(".") : map1.parent_path());
    passes.emplace_back("pass1", RunPass(args, dataset / "pass1", {}, map1, out_dir / "pass1", std::nullopt));
    // Pass 2 is scored in the map's frame: pass 1's alignment to the ground truth, not
    // a new one (the paper's Table III).
    std::optional<Eigen::Isometry3d> alignment;
    if (passes[0].second.ate.has_value()) alignment = passes[0].second.ate->T_gt_est;
    passes.emplace_back("pass2", RunPass(args, dataset / "pass2", map1, {}, out_dir / "pass2", alignment));
  } else {
    passes.emplace_back(dataset.filename().string(),
                        RunPass(args, dataset, args.map_in, args.map_out, out_dir, std::nullopt));
  }
  fmt::print("\n{:<8} {:>6} {:>10} {:>9} {:>9} {:>10} {:>10} {:>10}\n", "sequence", "frames", "localized",
             "keyframes", "points", "track ms", "ATE rmse m", "ATE max m");
  for (const auto& [name, pass] : passes) PrintPass(name, pass, !(two_pass && name == "pass2"));
  PrintLoopSegmentation(passes);
  fmt::print("outputs in {}\n", out_dir.string());
  return 0;
}

}  // namespace

void AddRunCommand(CLI::App& app, std::function<int()>* action) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run", "Run the SLAM core on a sequence (TUM layout), or on both passes of a generated dataset");
  cmd->add_option("dataset", args->dataset, "A TUM-layout sequence, or a dataset with pass1/ and pass2/")
      ->required();
  // Checked by slam::ParseSlamMode, whose error is one line like every other.
  cmd->add_option("--mode", args->mode, "plain, mask-moveable or mutual");
  cmd->add_option("--masks", args->masks,
                  "'gt' (the dataset's masks, used as they are) or a folder of external masks (refined in "
                  "the loop in mutual mode)");
  cmd->add_option("--segmenter", args->segmenter,
                  "Simulated segmenter preset on the dataset's ground-truth masks (mutual: refined in the loop; "
                  "mask-moveable: raw)")
      ->check(CLI::IsMember(seg::SimulatedSegmenterOptions::PresetNames()));
  cmd->add_option("--seed", args->seed, "Seed of the simulated segmenter")->capture_default_str();
  cmd->add_option("--map-in", args->map_in, "Localize on this long-term map (single sequence)");
  cmd->add_option("--map-out", args->map_out, "Write the long-term map here (and a .ply beside it)");
  cmd->add_option("--out", args->out_dir, "Output folder (default DATASET/run_MODE)");
  cmd->add_option("--frames", args->frames, "Only the first N frames of each sequence (0 = all)");
  cmd->add_option("--camera", args->camera_file,
                  "camera.yaml to use instead of the sequence's own (for a real sequence without one)");
  cmd->add_option("--tracker", args->tracker_options,
                  "Override a tracker option, NAME=VALUE (repeatable; see slam/tracker.h)");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress bar");
  cmd->callback([args, action] { *action = [args] { return RunRun(*args); }; });
}

}  // namespace segslam::harness
