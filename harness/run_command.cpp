// `segslam run`: the SLAM core over a sequence, or over both passes of a generated
// dataset (pass 1 builds the long-term map, pass 2 localizes on it: the paper's
// relocalization protocol). In mutual mode with a segmenter (--segmenter or --masks DIR)
// it runs the paper's loop, writes the refined masks and, on a sequence with ground-truth
// masks, scores raw vs refined masks with SLAM's poses.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include <fmt/core.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "harness/cli_numbers.h"
#include "harness/commands.h"
#include "harness/interrupt.h"
#include "harness/progress_bar.h"
#include "harness/dataset_run.h"
#include "harness/slam_runner.h"
#include "harness/trajectory_metrics.h"
#include "seg/simulated_segmenter.h"

namespace segslam::harness {

namespace fs = std::filesystem;

namespace {

struct RunArgs {
  std::string dataset;
  RunConfigWords words;   // --mode, --masks, --segmenter, --seed, --strength, --segmenter-option
  DatasetRunOptions run;  // filled by the other options of the same names
  std::string out_dir;
  bool quiet = false;
};

// Real sequences have long names ("rgbd_dataset_freiburg3_walking_xyz"); the column fits them.
int NameWidth(const std::vector<PassRun>& passes) {
  size_t width = 8;
  for (const PassRun& pass : passes) width = std::max(width, pass.name.size());
  return static_cast<int>(width);
}

void PrintPass(const PassRun& pass, int name_width) {
  const SlamRunResult& run = pass.run;
  fmt::print("{:<{}} {:>6} {:>9.1f}% {:>9} {:>9} {:>10.2f}", pass.name, name_width, run.frames.size(),
             100 * run.LocalizedShare(),
             run.keyframes, run.map_points, run.MedianTrackingMs());
  if (pass.ate.has_value()) {
    fmt::print(" {:>10.4f} {:>10.4f}  {}\n", pass.ate->translation_m.rmse, pass.ate->translation_m.max,
               pass.aligned ? "aligned" : "map frame");
  } else {
    fmt::print(" {:>10} {:>10}\n", "n/a", "n/a");
  }
}

// A map dropped and begun anew (slam::TrackerOptions::reset_map_keyframes) explains a
// low localized share, so it is said where it happened.
void PrintMapResets(const std::vector<PassRun>& passes) {
  for (const PassRun& pass : passes) {
    std::vector<std::string> frames;
    for (const slam::FrameResult& frame : pass.run.frames) {
      if (frame.map_reset) frames.push_back(std::to_string(frame.frame_index));
    }
    if (frames.empty()) continue;
    fmt::print("{}: a young map stayed lost and was dropped at frame {} to begin anew; the frames before count as lost\n",
               pass.name, fmt::join(frames, ", "));
  }
}

// A pass's start tracked again once its instances were judged (slam::TrackerOptions::
// retrack_map_start) changes its first poses, so it is said too.
void PrintRetrackedStarts(const std::vector<PassRun>& passes) {
  for (const PassRun& pass : passes) {
    const auto retracked = std::count_if(pass.run.frames.begin(), pass.run.frames.end(),
                                         [](const slam::FrameResult& frame) { return frame.retracked; });
    if (retracked == 0) continue;
    fmt::print("{}: its first {} frames were tracked again once their instances were judged, with what stood still in view\n",
               pass.name, retracked);
  }
}

std::string Points(double value) { return std::isnan(value) ? "  n/a" : fmt::format("{:5.1f}", 100 * value); }

// The segmentation-in-the-loop table, as seg-eval prints it with ground-truth poses.
void PrintLoopSegmentation(const std::vector<PassRun>& passes) {
  const int name_width = NameWidth(passes);
  bool header = false;
  for (const PassRun& pass : passes) {
    if (!pass.run.segmentation.has_value()) continue;
    const LoopSegmentationScores& s = *pass.run.segmentation;
    if (!header) {
      fmt::print("\nSegmentation in the loop (SLAM poses), segmenter {}\n", s.segmenter);
      fmt::print("{:<{}} {:>6} | {:>6} {:>6} {:>6} | {:>6} {:>6} {:>6} | {:>6} {:>6} {:>6}\n", "sequence", name_width,
                 "frames", "mAP", "AP50", "mIoU", "mAP", "AP50", "mIoU", "dmAP", "dAP50", "dmIoU");
      fmt::print("{:<{}} {:>6} | {:^20} | {:^20} | {:^20}\n", "", name_width, "", "raw", "refined", "refined - raw");
      header = true;
    }
    fmt::print("{:<{}} {:>6} | {} {} {} | {} {} {} | {} {} {}\n", pass.name, name_width, pass.run.frames.size(),
               Points(s.raw.mAP),
               Points(s.raw.AP50), Points(s.raw.mIoU), Points(s.refined.mAP), Points(s.refined.AP50),
               Points(s.refined.mIoU), Points(s.refined.mAP - s.raw.mAP), Points(s.refined.AP50 - s.raw.AP50),
               Points(s.refined.mIoU - s.raw.mIoU));
  }
  if (header) fmt::print("(points: percent; seg.json and refined_masks/ beside each trajectory)\n");
}

int RunRun(const RunArgs& args) {
  DatasetRunOptions options = args.run;
  // Before anything is printed, read or written.
  options.run = args.words.ToConfig("run");
  CheckDatasetRunOptions(options);
  const fs::path dataset(args.dataset);
  const std::string mode = options.run.ModeName();
  const fs::path out_dir = args.out_dir.empty() ? dataset / ("run_" + mode) : fs::path(args.out_dir);
  fmt::print("segslam run: mode {}, masks {}{}{}\n", mode, options.run.masks.Describe(),
             options.run.RefinesMasks() ? ", refined in the loop" : "",
             options.refiner_options.empty() ? ""
                                             : " with " + fmt::format("{}", fmt::join(options.refiner_options, " ")));
  // One progress bar per pass; each pass's rate counts from the end of the previous one.
  std::optional<ProgressBar> bar;
  std::string bar_pass;
  auto start = std::chrono::steady_clock::now();
  const std::atomic<bool>* cancel = InstallInterruptFlag();
  options.on_frame = [&](const std::string& pass, int done, int total) {
    if (cancel->load()) throw Error("run: cancelled");
    if (args.quiet) return;
    if (!bar.has_value() || bar_pass != pass) {
      if (bar.has_value()) bar->Finish();
      bar.emplace(fmt::format("run {} {}", mode, pass));
      bar_pass = pass;
    }
    const auto now = std::chrono::steady_clock::now();
    bar->Update(done, total, done / std::max(std::chrono::duration<double>(now - start).count(), 1e-9));
    if (done == total) start = now;
  };
  const std::vector<PassRun> passes = RunDataset(dataset, out_dir, options);
  if (bar.has_value()) bar->Finish();
  const int name_width = NameWidth(passes);
  fmt::print("\n{:<{}} {:>6} {:>10} {:>9} {:>9} {:>10} {:>10} {:>10}\n", "sequence", name_width, "frames",
             "localized", "keyframes", "points", "track ms", "ATE rmse m", "ATE max m");
  for (const PassRun& pass : passes) PrintPass(pass, name_width);
  PrintMapResets(passes);
  PrintRetrackedStarts(passes);
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
  // Checked by MakeRunConfig, whose error is one line like every other.
  cmd->add_option("--mode", args->words.mode,
                  "plain, mask-moveable, mutual, mutual-sparse (mutual judging from sparse features, as the "
                  "paper) or oracle (mutual with the true moving/static verdicts of a generated dataset)");
  cmd->add_option("--masks", args->words.masks,
                  "'gt' (the dataset's masks, used as they are) or a folder of external masks (refined in "
                  "the loop in the mutual modes)");
  cmd->add_option("--segmenter", args->words.segmenter,
                  "Simulated segmenter preset on the dataset's ground-truth masks (mutual: refined in the loop; "
                  "mask-moveable: raw)")
      ->check(CLI::IsMember(seg::SimulatedSegmenterOptions::PresetNames()));
  cmd->add_option("--seed", args->words.seed, "Seed of the simulated segmenter")->capture_default_str();
  cmd->add_option("--strength", args->words.strength,
                  "Scale of the simulated segmenter's errors (0 = ground truth, 1 = the preset, 2 = twice as bad)")
      ->check(NumberIn(0, 10))
      ->capture_default_str();
  cmd->add_option("--segmenter-option", args->words.segmenter_options,
                  "Override a field of the simulated segmenter's preset, NAME=VALUE (repeatable; the fields are "
                  "those of seg/simulated_segmenter_options.h), to tell which of its errors a run depends on");
  cmd->add_option("--map-in", args->run.map_in, "Localize on this long-term map (single sequence)");
  cmd->add_option("--map-out", args->run.map_out, "Write the long-term map here (and a .ply beside it)");
  cmd->add_option("--out,-o", args->out_dir, "Output folder (default DATASET/run_MODE)");
  cmd->add_option("--frames", args->run.frames, "Only the first N frames of each sequence (0 = all)")
      ->check(WholeNumberIn(0, kMaxFrames, "0 = all"));
  cmd->add_option("--camera", args->run.camera_file,
                  "camera.yaml to use instead of the sequence's own (for a real sequence without one)");
  cmd->add_option("--tracker", args->run.tracker_options,
                  "Override a tracker option, NAME=VALUE (repeatable; `segslam options tracker` lists them)");
  cmd->add_option("--refiner", args->run.refiner_options,
                  "Override a refinement option of the mutual loop, NAME=VALUE (repeatable; `segslam options refiner` lists them)");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress bar");
  cmd->callback([args, action] { *action = [args] { return RunRun(*args); }; });
}

}  // namespace segslam::harness
