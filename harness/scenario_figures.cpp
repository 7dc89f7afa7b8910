// The figures of a scenario report (harness/scenario_figures.h): top views and position
// errors of both passes for the run of median ATE of each mode, and one frame of pass 1
// of the mutual run as the paper's Figs. 5 (masks) and 6 (features).
#include "harness/scenario_figures.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <tuple>

#include <fmt/format.h>

#include "core/error.h"
#include "core/instances.h"
#include "core/json_file.h"
#include "core/pose.h"
#include "core/tum_dataset.h"
#include "harness/interrupt.h"
#include "harness/report_figures.h"
#include "harness/slam_runner.h"
#include "harness/trajectory_metrics.h"
#include "seg/external_masks.h"
#include "seg/metrics.h"
#include "seg/simulated_segmenter.h"

namespace segslam::harness {

namespace {

constexpr const char* kMaskFigureFile = "figures/masks_raw_vs_refined.png";
constexpr const char* kFeatureFigureFile = "figures/features_kept_vs_dropped.png";

// The run of `mode` standing for its mode in the figures: the one whose ATE on `pass` is
// nearest the median over repeats.
struct MedianAteRun {
  const RepeatRun* run = nullptr;
  const PassEvaluation* pass = nullptr;
};
std::optional<MedianAteRun> FindMedianAteRun(const ScenarioReport& report, const std::string& pass,
                                             const std::string& mode) {
  const Spread* spread = FindSpread(report.spreads, pass, mode, "ate_rmse_m");
  if (spread == nullptr) return std::nullopt;
  std::optional<MedianAteRun> chosen;
  double best = std::numeric_limits<double>::infinity();
  for (const RepeatRun& run : report.runs) {
    if (run.mode != mode) continue;
    for (const PassEvaluation& evaluation : run.evaluation.passes) {
      if (evaluation.name != pass || !evaluation.ate_m.has_value()) continue;
      const double distance = std::abs(evaluation.ate_m->rmse - spread->median);
      if (distance < best) {
        best = distance;
        chosen = MedianAteRun{&run, &evaluation};
      }
    }
  }
  return chosen;
}

// The frames of pass 1 the runs processed (--frames limits them).
int FramesRun(const TumSequence& sequence, const ScenarioReport& report) {
  const int size = static_cast<int>(sequence.size());
  return report.frames_per_pass > 0 ? std::min(report.frames_per_pass, size) : size;
}

// A frame's masks in the external-mask layout (seg/external_masks.h), as the mutual loop
// writes its refined masks (on the stored images), in the geometry of the sequence's frames.
seg::FrameSegmentation ReadMasksInExternalLayout(const TumSequence& sequence, const std::filesystem::path& dir,
                                                 const std::string& stem, cv::Size frame_size, int frame_index) {
  const std::filesystem::path png = dir / (stem + ".png");
  const std::filesystem::path json = dir / (stem + ".json");
  return seg::ExternalMasksToSegmentation(sequence.LoadInstanceMask(png),
                                          seg::ParseExternalMaskTable(ReadJsonFile(json), json.string()), frame_size,
                                          frame_index, png.string());
}

std::size_t CountInstances(const cv::Mat& ids) {
  std::set<std::uint16_t> seen;
  for (int row = 0; row < ids.rows; ++row) {
    const auto* pixel = ids.ptr<std::uint16_t>(row);
    for (int col = 0; col < ids.cols; ++col) {
      if (pixel[col] != 0) seen.insert(pixel[col]);
    }
  }
  return seen.size();
}

// Fig. 5: ground truth, raw and refined masks of one frame of pass 1 of `run`.
void DrawMaskFigure(const ScenarioReport& report, const RepeatRun& run, const std::filesystem::path& out) {
  if (report.bench.segmenter == "gt") throw Error("the mutual mode ran on ground-truth masks: nothing was refined");
  const std::filesystem::path pass_dir = std::filesystem::path(report.dataset_dir) / "pass1";
  const std::filesystem::path refined_dir = report.report_dir / run.run_dir / "pass1" / "refined_masks";
  const TumSequence sequence = TumSequence::Open(pass_dir);
  const InstanceTable gt_table = InstanceTable::Read(pass_dir / "instances.json");
  // The raw masks are not saved: the simulated segmenter draws each frame from (seed,
  // frame index) alone, so with the run's preset and seed it gives again exactly the
  // masks the loop refined.
  seg::SimulatedSegmenterOptions preset = seg::SimulatedSegmenterOptions::Preset(report.bench.segmenter);
  preset.strength = report.bench.segmenter_strength;
  seg::SimulatedSegmenter segmenter(pass_dir, preset, run.seed, report.bench.segmenter);

  // A dozen evenly spaced candidates keep this cheap on long sequences. The figure should
  // show refinement at work: frames with two or more ground-truth instances first, then
  // the largest mIoU gain of refined over raw, then the most instances.
  constexpr int kCandidates = 12;
  struct Candidate {
    RgbdFrame frame;
    cv::Mat gt_ids;
    seg::FrameSegmentation raw, refined;
    bool several_instances = false;
    double gain = 0;
    std::size_t instances = 0;
    bool BetterThan(const Candidate& other) const {
      return std::tie(several_instances, gain, instances) > std::tie(other.several_instances, other.gain, other.instances);
    }
  };
  std::optional<Candidate> best;
  const int frames = FramesRun(sequence, report);
  const int candidates = std::min(kCandidates, frames);
  for (int c = 0; c < candidates; ++c) {
    const int i = candidates <= 1 ? 0 : c * (frames - 1) / (candidates - 1);
    Candidate candidate;
    candidate.frame = sequence.LoadFrame(static_cast<std::size_t>(i));
    candidate.frame.index = i;
    const std::string stem = sequence.FrameStem(static_cast<std::size_t>(i));
    candidate.gt_ids = sequence.LoadInstanceMask(pass_dir / "masks" / (stem + ".png"));
    candidate.raw = segmenter.Segment(candidate.frame);
    candidate.refined = ReadMasksInExternalLayout(sequence, refined_dir, stem, candidate.frame.color_bgr.size(), i);
    const seg::EvaluationOptions scoring;
    const double raw_miou = seg::SegmentationEvaluator::ScoreFrame(scoring, candidate.gt_ids, gt_table, candidate.raw).mIoU;
    const double refined_miou =
        seg::SegmentationEvaluator::ScoreFrame(scoring, candidate.gt_ids, gt_table, candidate.refined).mIoU;
    // No class in view: nothing to compare, the frame goes last.
    candidate.gain = std::isnan(raw_miou) || std::isnan(refined_miou) ? -std::numeric_limits<double>::infinity()
                                                                        : refined_miou - raw_miou;
    candidate.instances = CountInstances(candidate.gt_ids);
    candidate.several_instances = candidate.instances >= 2;
    if (!best.has_value() || candidate.BetterThan(*best)) best = std::move(candidate);
  }
  if (!best.has_value()) throw Error("pass 1 of " + run.run_dir + " has no frames");
  WriteFigure(out, DrawMaskComparison(best->frame.color_bgr, best->gt_ids, gt_table, best->raw, best->refined));
}

// Fig. 6: the features of one frame of pass 1 of `run`, kept or dropped by the judgement.
void DrawFeatureFigure(const ScenarioReport& report, const RepeatRun& run, const std::filesystem::path& out) {
  const std::filesystem::path pass_dir = std::filesystem::path(report.dataset_dir) / "pass1";
  const TumSequence sequence = TumSequence::Open(pass_dir);
  // Feature records are not written to disk (they would outweigh the rest of a run), and
  // keeping every repeat's in memory until the median is known costs more than this: pass
  // 1 of the chosen run is run again with record_features. SLAM is deterministic given
  // the segmenter's seed, so this is the same run, frame for frame, and its judgement used
  // the refined masks the run wrote.
  SlamRunOptions options;
  options.run = report.bench.RunConfigFor("mutual", run.seed);
  if (options.run.RefinesMasks()) options.refiner = report.bench.LoopRefinerOptions();
  options.max_frames = FramesRun(sequence, report);
  options.tracker = report.bench.TrackerOverrides();
  options.tracker.record_features = true;
  // A minute of SLAM again: Ctrl-C stops it (the scenario run then ends as interrupted).
  options.on_frame = [](int, int) {
    if (InterruptRequested()) throw Error("interrupted");
  };
  const SlamRunResult rerun = RunSlamOnSequence(sequence, options);
  const std::optional<std::size_t> chosen = PickFeatureFigureFrame(rerun.frames);
  if (!chosen.has_value()) throw Error("no frame of pass 1 has feature records");
  const int frame_index = static_cast<int>(*chosen);
  const std::string stem = sequence.FrameStem(*chosen);
  const std::filesystem::path judged_masks =
      !options.run.RefinesMasks() ? pass_dir / "masks" / (stem + ".png")
                                : report.report_dir / run.run_dir / "pass1" / "refined_masks" / (stem + ".png");
  const RgbdFrame frame = sequence.LoadFrame(*chosen);
  const std::string title =
      fmt::format("{} pass 1, frame {}, mutual{}", report.scenario_name, frame_index,
                  !options.run.RefinesMasks() ? " on ground-truth masks" : fmt::format(" (seed {})", run.seed));
  WriteFigure(out, DrawFeatureKinds(frame.color_bgr, sequence.LoadInstanceMask(judged_masks), rerun.frames[*chosen], title));
}

// Every figure the report may show, in its order.
std::vector<PlannedFigure> PlannedFigures() {
  return {{"figures/trajectories_pass1.png",
           "Top view of pass 1: ground truth and, per mode, the run of median ATE, aligned (as the paper's Fig. 4)"},
          {"figures/trajectories_pass2.png",
           "Top view of pass 2, localized on pass 1's map, in pass 1's aligned frame (as the paper's Fig. 4)"},
          {"figures/error_pass1.png",
           "Position error of pass 1 frame by frame, for the same runs, after the ATE's alignment: where each "
           "mode's error builds up"},
          {"figures/error_pass2.png",
           "Position error of pass 2 frame by frame, in pass 1's aligned frame as Table III; gaps are frames "
           "not localized"},
          {kMaskFigureFile, "Raw vs refined masks of the mutual loop (as the paper's Fig. 5)"},
          {kFeatureFigureFile, "Matched features kept vs dropped as moving (as the paper's Fig. 6)"}};
}

}  // namespace

std::vector<PlannedFigure> PresentFigures(const std::filesystem::path& report_dir) {
  std::vector<PlannedFigure> present;
  for (const PlannedFigure& figure : PlannedFigures()) {
    if (!report_dir.empty() && std::filesystem::exists(report_dir / figure.file)) present.push_back(figure);
  }
  return present;
}

std::vector<std::string> DrawReportFigures(const ScenarioReport& report) {
  std::vector<std::string> problems;
  for (const std::string& pass : kScenarioPasses) {
    const std::string file = "figures/trajectories_" + pass + ".png";
    const std::string error_file = "figures/error_" + pass + ".png";
    std::string drawing = file;
    try {
      NamedTrajectory ground_truth{"ground truth",
                                   ReadTumTrajectory(std::filesystem::path(report.dataset_dir) / pass / "groundtruth.txt")};
      std::vector<NamedTrajectory> estimates;
      for (const std::string& mode : report.bench.modes) {
        const std::optional<MedianAteRun> chosen = FindMedianAteRun(report, pass, mode);
        if (!chosen.has_value()) continue;
        std::vector<StampedPose> poses =
            ReadTumTrajectory(report.report_dir / chosen->run->run_dir / pass / "trajectory.txt");
        for (StampedPose& pose : poses) pose.T_wc = chosen->pass->T_gt_est * pose.T_wc;
        estimates.push_back({report.bench.ModeIsDeterministic(mode) ? mode
                                                                    : fmt::format("{} (seed {})", mode, chosen->run->seed),
                             std::move(poses)});
      }
      TopViewOptions options;
      options.title = fmt::format("{} {}: top view", report.scenario_name, pass);
      std::filesystem::create_directories(report.report_dir / "figures");
      WriteFigure(report.report_dir / file, DrawTopView(options, ground_truth, estimates).image);

      drawing = error_file;
      if (ground_truth.poses.size() < 2) throw Error("fewer than two ground-truth poses");
      std::vector<double> seconds;
      for (const StampedPose& pose : ground_truth.poses) {
        seconds.push_back(pose.stamp_s - ground_truth.poses.front().stamp_s);
      }
      std::vector<PlotSeries> series;
      for (const NamedTrajectory& estimate : estimates) {
        series.push_back({estimate.name, PositionErrorPerFrame(ground_truth.poses, estimate.poses), {}, {}});
      }
      LinePlotOptions plot;
      plot.title = fmt::format("{} {}: position error per frame", report.scenario_name, pass);
      plot.x_label = "time [s]";
      plot.y_label = "position error [m]";
      plot.size = cv::Size(900, 420);
      plot.markers = false;
      WriteFigure(report.report_dir / error_file, DrawLinePlot(plot, seconds, series).image);
    } catch (const Error& e) {
      problems.push_back(drawing + ": " + e.what());
    }
  }
  // Figs. 5 and 6 show one frame of pass 1 of the mutual run of median ATE. OpenCV and
  // the rerun may throw more than segslam::Error; a figure is never worth the report.
  const std::optional<MedianAteRun> mutual = FindMedianAteRun(report, "pass1", "mutual");
  try {
    if (!mutual.has_value()) throw Error("the mutual mode did not run (or has no pass-1 ATE)");
    DrawMaskFigure(report, *mutual->run, report.report_dir / kMaskFigureFile);
  } catch (const std::exception& e) {
    problems.push_back(std::string(kMaskFigureFile) + ": " + e.what());
  }
  try {
    if (!mutual.has_value()) throw Error("the mutual mode did not run (or has no pass-1 ATE)");
    DrawFeatureFigure(report, *mutual->run, report.report_dir / kFeatureFigureFile);
  } catch (const std::exception& e) {
    problems.push_back(std::string(kFeatureFigureFile) + ": " + e.what());
  }
  return problems;
}

}  // namespace segslam::harness
