// `segslam seg-eval DATASET`: runs a segmenter and the paper's refinement over both
// passes with ground-truth poses and prints raw vs refined mAP, AP50 and mIoU, as the
// paper's Tables II and IV, with overlay pictures of the last frame (its Fig. 5).
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/instances.h"
#include "core/tracks.h"
#include "core/tum_dataset.h"
#include "harness/cli_numbers.h"
#include "harness/commands.h"
#include "harness/interrupt.h"
#include "harness/pictures.h"
#include "harness/progress_bar.h"
#include "harness/run_config.h"
#include "seg/external_masks.h"
#include "seg/metrics.h"
#include "seg/refiner.h"
#include "seg/refiner_options.h"
#include "seg/sequence_evaluation.h"
#include "seg/simulated_segmenter.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

struct SegEvalArgs {
  std::string dataset;
  std::string segmenter = "fcis-like";
  double strength = 1.0;
  std::uint64_t seed = 1;
  std::string masks_dir;
  std::string poses = "gt";
  bool object_motion = true;
  std::string out_dir;
  std::vector<std::string> refiner_options;  // NAME=VALUE overrides of RefinerOptions
  std::vector<std::string> segmenter_options;  // NAME=VALUE overrides of the preset
};

// The sequences of a dataset: pass1/ and pass2/ of a generated one, or the directory
// itself when it is one sequence.
std::vector<fs::path> SequencesOf(const fs::path& dataset) {
  std::vector<fs::path> sequences;
  for (const char* pass : {"pass1", "pass2"}) {
    if (fs::is_directory(dataset / pass)) sequences.push_back(dataset / pass);
  }
  if (sequences.empty()) sequences.push_back(dataset);
  return sequences;
}

// Made when the first result is written, so that a refused dataset, mask folder or option
// leaves no empty output folder behind.
void CreateOutputFolder(const fs::path& out_dir) {
  std::error_code error;
  fs::create_directories(out_dir, error);
  if (error) throw FileError(out_dir, "cannot create: " + error.message());
}

seg::SequenceSegEval EvaluateSequence(const SegEvalArgs& args, const fs::path& dir,
                                      const fs::path& out_dir) {
  std::unique_ptr<seg::Segmenter> segmenter;
  if (!args.masks_dir.empty()) {
    segmenter = std::make_unique<seg::ExternalMaskSegmenter>(args.masks_dir, TumSequence::Open(dir));
  } else {
    const seg::SimulatedSegmenterOptions options =
        SimulatedSegmenterOptionsFor(args.segmenter, args.strength, args.segmenter_options);
    segmenter = std::make_unique<seg::SimulatedSegmenter>(dir, options, args.seed,
                                                          PresetWithOverrides(args.segmenter, args.segmenter_options));
  }

  seg::SegEvalOptions options;
  for (const std::string& assignment : args.refiner_options) {
    seg::SetRefinerOption(&options.refiner, assignment);
  }
  options.object_motion = args.object_motion;
  ProgressBar bar("seg-eval " + dir.filename().string());
  const auto start = std::chrono::steady_clock::now();
  const std::atomic<bool>* cancel = InstallInterruptFlag();
  options.on_frame = [&](int done, int total) {
    if (cancel->load()) throw Error("seg-eval: cancelled");
    const double elapsed_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    bar.Update(done, total, done / elapsed_s);
  };
  seg::SequenceSegEval result = seg::EvaluateSequenceWithGroundTruthPoses(options, dir, *segmenter);
  bar.Finish();

  // The paper's Fig. 5: the last frame's ground truth, initial and refined instances.
  if (!out_dir.empty() && result.frames > 0) {
    CreateOutputFolder(out_dir);
    const cv::Size size = result.last_gt_ids.size();
    const cv::Mat row = CaptionedRow(
        {OverlayPicture(result.last_color_bgr, result.last_gt_ids),
         OverlayPicture(result.last_color_bgr, result.last_initial.ToIdImage(size)),
         OverlayPicture(result.last_color_bgr, result.last_refined.ToIdImage(size))},
        {"ground truth", "initial (" + segmenter->name() + ")", "refined"});
    WriteImageAtomically(out_dir / (dir.filename().string() + "_last_frame.png"), row);
  }
  return result;
}

std::string Points(double value) { return std::isnan(value) ? "  n/a" : fmt::format("{:5.1f}", 100 * value); }

int RunSegEval(const SegEvalArgs& args) {
  if (args.poses != "gt") {
    throw Error("seg-eval: --poses " + args.poses +
                ": only 'gt' is available (poses from SLAM come with `segslam run`)");
  }
  const fs::path out_dir = args.out_dir.empty() ? fs::path(args.dataset) / "seg_eval" : fs::path(args.out_dir);

  std::vector<seg::SequenceSegEval> results;
  for (const fs::path& dir : SequencesOf(args.dataset)) results.push_back(EvaluateSequence(args, dir, out_dir));

  const std::string segmenter_name =
      args.masks_dir.empty() ? fmt::format("{} (strength {})", args.segmenter, args.strength)
                             : "external masks " + args.masks_dir;
  fmt::print("\nSegmentation on {} with ground-truth poses, segmenter {}\n", args.dataset, segmenter_name);
  fmt::print("{:<10} {:>6} | {:>6} {:>6} {:>6} | {:>6} {:>6} {:>6} | {:>6} {:>6} {:>6}\n", "sequence",
             "frames", "mAP", "AP50", "mIoU", "mAP", "AP50", "mIoU", "dmAP", "dAP50", "dmIoU");
  fmt::print("{:<10} {:>6} | {:^20} | {:^20} | {:^20}\n", "", "", "raw", "refined", "refined - raw");
  nlohmann::json json = {{"dataset", args.dataset},
                         {"segmenter", segmenter_name},
                         {"seed", args.seed},
                         {"poses", args.poses},
                         {"object_motion", args.object_motion}};
  for (const auto& r : results) {
    fmt::print("{:<10} {:>6} | {} {} {} | {} {} {} | {} {} {}\n", r.name, r.frames, Points(r.raw.mAP),
               Points(r.raw.AP50), Points(r.raw.mIoU), Points(r.refined.mAP), Points(r.refined.AP50),
               Points(r.refined.mIoU), Points(r.refined.mAP - r.raw.mAP),
               Points(r.refined.AP50 - r.raw.AP50), Points(r.refined.mIoU - r.raw.mIoU));
    fmt::print("{:<10} {:>6} | {} {} {} | {:^20} | {} {} {}   raw, scores >= {}\n", "", "", Points(r.raw_confident.mAP),
               Points(r.raw_confident.AP50), Points(r.raw_confident.mIoU), "", Points(r.refined.mAP - r.raw_confident.mAP),
               Points(r.refined.AP50 - r.raw_confident.AP50), Points(r.refined.mIoU - r.raw_confident.mIoU),
               r.raw_confident_min_score);
    json["sequences"].push_back({{"sequence", r.name},
                                 {"frames", r.frames},
                                 {"raw", r.raw.ToJson()},
                                 {"raw_confident", r.raw_confident.ToJson()},
                                 {"raw_confident_min_score", r.raw_confident_min_score},
                                 {"refined", r.refined.ToJson()},
                                 {"refine_ms_median", r.refine_ms_median},
                                 {"decisions",
                                  {{"new", r.decision_counts[0]},
                                   {"kept", r.decision_counts[1]},
                                   {"replaced", r.decision_counts[2]},
                                   {"added", r.decision_counts[3]},
                                   {"dropped", r.decision_counts[4]}}}});
    fmt::print("{:<10} decisions: kept {} replaced {} new {} added {} dropped {}\n", "",
               r.decision_counts[1], r.decision_counts[2], r.decision_counts[0],
               r.decision_counts[3], r.decision_counts[4]);
  }
  fmt::print("(points: percent; overlays of each sequence's last frame in {})\n", out_dir.string());
  CreateOutputFolder(out_dir);
  WriteFileAtomically(out_dir / "seg_eval.json", json.dump(2) + "\n");
  return 0;
}

}  // namespace

void AddSegEvalCommand(CLI::App& app, std::function<int()>* action) {
  auto args = std::make_shared<SegEvalArgs>();
  CLI::App* command = app.add_subcommand(
      "seg-eval", "Raw vs refined instance segmentation (mAP, AP50, mIoU) with ground-truth poses");
  command->add_option("dataset", args->dataset, "A generated dataset (pass1/, pass2/) or one sequence")
      ->required();
  command->add_option("--segmenter", args->segmenter, "Simulated segmenter preset (fcis-like, clean, ...)")
      ->capture_default_str();
  command->add_option("--strength", args->strength, "Scale of the simulated segmenter's errors")
      ->check(NumberIn(0, 10))
      ->capture_default_str();
  command->add_option("--seed", args->seed, "Seed of the simulated segmenter")->capture_default_str();
  command->add_option("--masks", args->masks_dir, "Use external masks from this folder instead");
  command->add_option("--poses", args->poses, "Camera poses for the refinement: gt")->capture_default_str();
  command->add_flag("!--no-object-motion", args->object_motion,
                    "Project moving objects with the camera motion only (as the paper)");
  command->add_option("--segmenter-option", args->segmenter_options,
                      "Override a simulated segmenter option, NAME=VALUE (repeatable; see seg/simulated_segmenter.h)");
  command->add_option("--refiner", args->refiner_options,
                      "Override a refiner option, NAME=VALUE (repeatable; `segslam options refiner` lists them)");
  command->add_option("--out,-o", args->out_dir, "Where to write seg_eval.json and pictures "
                                              "(default: DATASET/seg_eval)");
  command->callback([args, action] { *action = [args] { return RunSegEval(*args); }; });
}

}  // namespace segslam::harness
