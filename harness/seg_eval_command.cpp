// `segslam seg-eval DATASET`: runs a segmenter and the paper's refinement over both
// passes with ground-truth poses and prints raw vs refined mAP, AP50 and mIoU, as the
// paper's Tables II and IV, with overlay pictures of the last frame (its Fig. 5).
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/instances.h"
#include "core/tracks.h"
#include "core/tum_dataset.h"
#include "harness/commands.h"
#include "harness/interrupt.h"
#include "harness/pictures.h"
#include "harness/progress_bar.h"
#include "seg/external_masks.h"
#include "seg/metrics.h"
#include "seg/refiner.h"
#include "seg/simulated_segmenter.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
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

// The ground-truth instance of each region: the id it overlaps most in `gt_ids`.
std::uint16_t DominantGroundTruthId(const cv::Mat& region, const cv::Mat& gt_ids) {
  std::map<std::uint16_t, int> votes;
  for (int v = 0; v < region.rows; ++v) {
    const std::uint8_t* in = region.ptr<std::uint8_t>(v);
    const std::uint16_t* gt = gt_ids.ptr<std::uint16_t>(v);
    for (int u = 0; u < region.cols; ++u) {
      if (in[u] && gt[u]) ++votes[gt[u]];
    }
  }
  std::uint16_t best = 0;
  int best_votes = 0;
  for (const auto& [id, count] : votes) {
    if (count > best_votes) best = id, best_votes = count;
  }
  return best;
}

struct SequenceResult {
  std::string name;
  seg::SegmentationScores raw;
  seg::SegmentationScores refined;
  double refine_ms_median = 0;
  int frames = 0;
};

SequenceResult EvaluateSequence(const SegEvalArgs& args, const fs::path& dir,
                                const fs::path& out_dir) {
  const TumSequence sequence = TumSequence::Open(dir);
  if (!sequence.has_groundtruth() || sequence.groundtruth().size() != sequence.size()) {
    throw FileError(dir / "groundtruth.txt",
                    "seg-eval needs one ground-truth pose per frame (--poses gt)");
  }
  const InstanceTable instances = InstanceTable::Read(dir / "instances.json");
  std::optional<std::map<std::uint16_t, const ObjectTrack*>> track_of;
  std::vector<ObjectTrack> tracks;
  if (args.object_motion && fs::exists(dir / "tracks.json")) {
    tracks = ReadTracks(dir / "tracks.json");
    track_of.emplace();
    for (const auto& track : tracks) (*track_of)[track.instance_id] = &track;
  }

  std::unique_ptr<seg::Segmenter> segmenter;
  if (!args.masks_dir.empty()) {
    segmenter = std::make_unique<seg::ExternalMaskSegmenter>(args.masks_dir, sequence);
  } else {
    seg::SimulatedSegmenterOptions options = seg::SimulatedSegmenterOptions::Preset(args.segmenter);
    options.strength = args.strength;
    segmenter = std::make_unique<seg::SimulatedSegmenter>(dir, options, args.seed, args.segmenter);
  }

  seg::SegmentationRefiner refiner;
  seg::SegmentationEvaluator raw_scores, refined_scores;
  const PinholeCamera& camera = sequence.camera().intrinsics;
  const cv::Size size(camera.width, camera.height);
  ProgressBar bar("seg-eval " + dir.filename().string());
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> refine_ms;

  std::optional<seg::FrameSegmentation> previous_refined;
  cv::Mat previous_depth, previous_gt;
  RgbdFrame frame;
  seg::FrameSegmentation initial;
  seg::RefinementResult refinement;
  cv::Mat gt_ids;
  const std::atomic<bool>* cancel = InstallInterruptFlag();
  for (size_t i = 0; i < sequence.size(); ++i) {
    if (cancel->load()) throw Error("seg-eval: cancelled");
    frame = sequence.LoadFrame(i);
    frame.index = static_cast<int>(i);
    gt_ids = ReadInstanceMask(dir / "masks" / (fs::path(sequence.entries()[i].rgb_file).stem().string() + ".png"));
    initial = segmenter->Segment(frame);

    seg::RefinerInput input;
    input.previous_refined = previous_refined ? &*previous_refined : nullptr;
    input.previous_depth_m = previous_depth;
    input.T_wc_previous_fine = sequence.groundtruth()[i > 0 ? i - 1 : 0].T_wc;
    input.T_wc_current_coarse = sequence.groundtruth()[i].T_wc;
    input.current_initial = initial;
    input.camera = camera;
    // Moving objects are projected with their own ground-truth motion (with --poses gt,
    // every pose is the true one): T_cur_prev = T_cw(t) T_wo(t) T_ow(t-1) T_wc(t-1).
    if (previous_refined && track_of) {
      for (const auto& region : previous_refined->instances) {
        const std::uint16_t gt_id = DominantGroundTruthId(region.mask, previous_gt);
        const auto it = track_of->find(gt_id);
        if (gt_id == 0 || it == track_of->end() || it->second->samples.size() <= i) continue;
        const TrackSample& before = it->second->samples[i - 1];
        const TrackSample& now = it->second->samples[i];
        if (!before.present || !now.present || !before.moving) continue;
        input.instance_motion_prev[region.track_id] =
            input.T_wc_current_coarse.inverse() * now.T_world_object *
            before.T_world_object.inverse() * input.T_wc_previous_fine;
      }
    }
    const auto refine_start = std::chrono::steady_clock::now();
    refinement = refiner.Refine(input);
    refine_ms.push_back(std::chrono::duration<double, std::milli>(
                            std::chrono::steady_clock::now() - refine_start).count());

    raw_scores.AddFrame(gt_ids, instances, initial);
    refined_scores.AddFrame(gt_ids, instances, refinement.refined);
    previous_refined = refinement.refined;
    previous_depth = frame.depth_m;
    previous_gt = gt_ids;
    const double elapsed_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    bar.Update(static_cast<int>(i + 1), static_cast<int>(sequence.size()), (i + 1) / elapsed_s);
  }
  bar.Finish();

  // The paper's Fig. 5: the last frame's ground truth, initial and refined instances.
  if (!out_dir.empty() && sequence.size() > 0) {
    const cv::Mat row = CaptionedRow(
        {OverlayPicture(frame.color_bgr, gt_ids),
         OverlayPicture(frame.color_bgr, initial.ToIdImage(size)),
         OverlayPicture(frame.color_bgr, refinement.refined.ToIdImage(size))},
        {"ground truth", "initial (" + segmenter->name() + ")", "refined"});
    WriteImageAtomically(out_dir / (dir.filename().string() + "_last_frame.png"), row);
  }

  SequenceResult result;
  result.name = dir.filename().string();
  result.raw = raw_scores.Scores();
  result.refined = refined_scores.Scores();
  result.frames = static_cast<int>(sequence.size());
  std::sort(refine_ms.begin(), refine_ms.end());
  result.refine_ms_median = refine_ms.empty() ? 0 : refine_ms[refine_ms.size() / 2];
  return result;
}

std::string Points(double value) { return std::isnan(value) ? "  n/a" : fmt::format("{:5.1f}", 100 * value); }

int RunSegEval(const SegEvalArgs& args) {
  if (args.poses != "gt") {
    throw Error("seg-eval: --poses " + args.poses +
                ": only 'gt' is available (poses from SLAM come with `segslam run`)");
  }
  const fs::path out_dir = args.out_dir.empty() ? fs::path(args.dataset) / "seg_eval" : fs::path(args.out_dir);
  std::error_code error;
  fs::create_directories(out_dir, error);
  if (error) throw FileError(out_dir, "cannot create: " + error.message());

  std::vector<SequenceResult> results;
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
    json["sequences"].push_back({{"sequence", r.name},
                                 {"frames", r.frames},
                                 {"raw", r.raw.ToJson()},
                                 {"refined", r.refined.ToJson()},
                                 {"refine_ms_median", r.refine_ms_median}});
  }
  fmt::print("(points: percent; overlays of each sequence's last frame in {})\n", out_dir.string());
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
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--seed", args->seed, "Seed of the simulated segmenter")->capture_default_str();
  command->add_option("--masks", args->masks_dir, "Use external masks from this folder instead");
  command->add_option("--poses", args->poses, "Camera poses for the refinement: gt")->capture_default_str();
  command->add_flag("!--no-object-motion", args->object_motion,
                    "Project moving objects with the camera motion only (as the paper)");
  command->add_option("--out", args->out_dir, "Where to write seg_eval.json and pictures "
                                              "(default: DATASET/seg_eval)");
  command->callback([args, action] { *action = [args] { return RunSegEval(*args); }; });
}

}  // namespace segslam::harness
