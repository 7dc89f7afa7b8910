#include "harness/scenario_report.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <tuple>

#include <fmt/format.h>

#include "core/error.h"
#include "core/image_io.h"
#include "core/instances.h"
#include "core/json_file.h"
#include "core/pose.h"
#include "core/statistics.h"
#include "core/tum_dataset.h"
#include "harness/dataset_run.h"
#include "harness/interrupt.h"
#include "harness/machine.h"
#include "harness/report_figures.h"
#include "harness/slam_runner.h"
#include "harness/trajectory_metrics.h"
#include "seg/external_masks.h"
#include "seg/metrics.h"
#include "seg/refiner_option_overrides.h"
#include "seg/simulated_segmenter.h"
#include "slam/tracker_option_overrides.h"

namespace segslam::harness {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

const std::vector<std::string> kPasses = {"pass1", "pass2"};

bool Contains(const std::vector<std::string>& list, const std::string& value) {
  return std::find(list.begin(), list.end(), value) != list.end();
}

std::string Join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string text;
  for (std::size_t i = 0; i < parts.size(); ++i) text += (i ? separator : "") + parts[i];
  return text;
}

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = text.find(separator, start);
    parts.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) return parts;
    start = end + 1;
  }
}

nlohmann::json NumberJson(double value) { return std::isnan(value) ? nlohmann::json(nullptr) : nlohmann::json(value); }

// A table of the report with its heading and note, added to a ReportDocument.
struct Table {
  std::string title;
  std::string note;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

// XML needs the same five entities as HTML text.
// XML 1.0 cannot hold control characters other than tab, line feed and carriage return,
// not even as references: they are dropped.
std::string EscapeXml(const std::string& text) {
  std::string allowed;
  allowed.reserve(text.size());
  for (const char c : text) {
    if (static_cast<unsigned char>(c) >= 0x20 || c == '\t' || c == '\n' || c == '\r') allowed += c;
  }
  return EscapeHtml(allowed);
}

// "0.0123 [0.0101, 0.0150]" (median [min, max]); `scale` turns shares into percent.
// Runs without a value are named: "0.0123 (2 of 3 runs)".
std::string SpreadText(const Spread& s, int decimals, double scale = 1) {
  if (s.count == 0) return "n/a";
  std::string text = s.count == 1 ? fmt::format("{:.{}f}", s.median * scale, decimals)
                                  : fmt::format("{:.{}f} [{:.{}f}, {:.{}f}]", s.median * scale, decimals,
                                                s.min * scale, decimals, s.max * scale, decimals);
  if (s.count < s.runs) text += fmt::format(" ({} of {} runs)", s.count, s.runs);
  return text;
}

const Spread* FindSpread(const SpreadTable& table, const std::string& pass, const std::string& mode,
                         const std::string& metric) {
  const auto p = table.find(pass);
  if (p == table.end()) return nullptr;
  const auto m = p->second.find(mode);
  if (m == p->second.end()) return nullptr;
  const auto v = m->second.find(metric);
  return v == m->second.end() ? nullptr : &v->second;
}

std::string Cell(const SpreadTable& table, const std::string& pass, const std::string& mode, const std::string& metric,
                 int decimals, double scale = 1) {
  const Spread* s = FindSpread(table, pass, mode, metric);
  return s == nullptr ? "n/a" : SpreadText(*s, decimals, scale);
}

std::string ValueText(double value) { return std::isnan(value) ? "n/a" : fmt::format("{:.6g}", value); }

// The report's tables, in the layout of the paper's; each says what its cells are.
const char* const kSpreadNote = "median [min, max] over repeats; one number where a mode ran once.";

Table ExpectationsTable(const ScenarioReport& report) {
  Table checks{"Expectations", "Medians over repeats (ratios: of medians), against the scenario's expect: section.",
               {"metric", "threshold", "value", "result"}, {}};
  for (const ExpectationResult& r : report.checks) {
    checks.rows.push_back({r.expectation.name.text, r.expectation.Bounds(), ValueText(r.value), r.passed ? "PASS" : "FAIL"});
  }
  for (const std::string& name : report.not_checked) {
    checks.rows.push_back({name, "", "", "not checked: --modes leaves its mode out"});
  }
  return checks;
}

Table AteTable(const ScenarioReport& report) {
  Table ate{"ATE rmse [m] per sequence and mode (as the paper's Table I)",
            std::string(kSpreadNote) +
                " Pass 1 aligned to the ground truth (Horn); pass 2 in pass 1's aligned map frame. ATE covers the "
                "localized frames only, so each pass's share of them is given below it.",
            {"sequence"}, {}};
  for (const auto& mode : report.bench.modes) ate.header.push_back(mode);
  for (const auto& pass : kPasses) {
    std::vector<std::string> row = {report.scenario_name + " " + pass};
    std::vector<std::string> localized = {report.scenario_name + " " + pass + " localized [%]"};
    for (const auto& mode : report.bench.modes) {
      row.push_back(Cell(report.spreads, pass, mode, "ate_rmse_m", 4));
      localized.push_back(Cell(report.spreads, pass, mode, "localized_share", 1, 100));
    }
    ate.rows.push_back(row);
    ate.rows.push_back(localized);
  }
  return ate;
}

Table RpeTable(const ScenarioReport& report) {
  Table rpe{"RPE rmse per second: translation [m] / rotation [deg]",
            std::string(kSpreadNote) + " n/a: fewer than 2 pose pairs 1 s apart (results.json: rpe.missing says why).",
            {"sequence"},
            {}};
  for (const auto& mode : report.bench.modes) rpe.header.push_back(mode);
  for (const auto& pass : kPasses) {
    std::vector<std::string> row = {report.scenario_name + " " + pass};
    for (const auto& mode : report.bench.modes) {
      row.push_back(Cell(report.spreads, pass, mode, "rpe_trans_rmse_m", 4) + " / " +
                    Cell(report.spreads, pass, mode, "rpe_rot_rmse_deg", 3));
    }
    rpe.rows.push_back(row);
  }
  return rpe;
}

Table SegmentationTable(const ScenarioReport& report) {
  Table seg{"Segmentation in the loop, raw vs refined [%] (as the paper's Tables II and IV)",
            std::string(kSpreadNote) + " Scored against the ground-truth masks with SLAM's poses; segmenter " +
                report.bench.SegmenterLabel() + ".",
            {"sequence", "mode", "raw mAP", "raw AP50", "raw mIoU", "refined mAP", "refined AP50", "refined mIoU"},
            {}};
  for (const auto& pass : kPasses) {
    for (const auto& mode : report.bench.modes) {
      const Spread* raw = FindSpread(report.spreads, pass, mode, "seg_raw_map");
      if (raw == nullptr || raw->count == 0) continue;
      std::vector<std::string> row = {report.scenario_name + " " + pass, mode};
      for (const char* metric : {"seg_raw_map", "seg_raw_ap50", "seg_raw_miou", "seg_refined_map", "seg_refined_ap50",
                                 "seg_refined_miou"}) {
        row.push_back(Cell(report.spreads, pass, mode, metric, 1, 100));
      }
      seg.rows.push_back(row);
    }
  }
  if (seg.rows.empty()) seg.note = "No run scored masks (the mutual loop with a simulated segmenter writes seg.json).";
  return seg;
}

Table RelocalizationTable(const ScenarioReport& report) {
  // The ATE in the map frame is the paper's figure but includes pass 1's own error at each
  // place; the map-relative columns leave it out (harness/map_relative_error.h).
  const MapRelativeOptions map_relative;
  Table reloc{"Relocalization in pass 2 on pass 1's long-term map (as the paper's Table III)",
              std::string(kSpreadNote) +
                  " ATE in the map frame, not re-aligned (the paper's figure; it includes pass 1's map error). "
                  "Map-relative: each pass-2 pose against pass 1's estimate at the nearest pass-1 place (pass 1's "
                  "error drops out), rmse over frames with a pose; within: the share of frames with a place that "
                  "have a pose within " +
                  fmt::format("{:g} m and {:g} deg", map_relative.within_translation_m, map_relative.within_rotation_deg) +
                  " of it (results.json: map_relative counts frames without a place).",
              {"mode", "localized [%]", "ATE rmse [m]", "ATE max [m]", "map-relative rmse [m]",
               "map-relative rmse [deg]", "within [%]"},
              {}};
  for (const auto& mode : report.bench.modes) {
    reloc.rows.push_back({mode, Cell(report.spreads, "pass2", mode, "localized_share", 1, 100),
                          Cell(report.spreads, "pass2", mode, "ate_rmse_m", 4),
                          Cell(report.spreads, "pass2", mode, "ate_max_m", 4),
                          Cell(report.spreads, "pass2", mode, "reloc_trans_rmse_m", 4),
                          Cell(report.spreads, "pass2", mode, "reloc_rot_rmse_deg", 3),
                          Cell(report.spreads, "pass2", mode, "reloc_within_share", 1, 100)});
  }
  return reloc;
}

// Rows only for mutual: plain knows no instances; mask-moveable drops moveable instances
// unjudged.
Table MovingDetectionTable(const ScenarioReport& report) {
  Table moving{"Moving-object detection vs the ground-truth tracks [%]",
               std::string(kSpreadNote) +
                   " Precision and recall over instances SLAM judged, each (frame, instance) once; coverage: "
                   "the share of moving instances SLAM saw (a feature on them, judged or not) that it judged "
                   "moving. Moving features: the share of a frame's features that lie on truly moving "
                   "objects, mean and max over the frames (how much of what SLAM saw moved). Truth: "
                   "tracks.json's moving flag.",
               {"sequence", "mode", "precision", "recall", "coverage", "moving features, mean", "moving features, max"},
               {}};
  for (const auto& pass : kPasses) {
    for (const auto& mode : report.bench.modes) {
      if (mode != "mutual") continue;
      moving.rows.push_back({report.scenario_name + " " + pass, mode,
                             Cell(report.spreads, pass, mode, "moving_precision", 1, 100),
                             Cell(report.spreads, pass, mode, "moving_recall", 1, 100),
                             Cell(report.spreads, pass, mode, "moving_coverage", 1, 100),
                             Cell(report.spreads, pass, mode, "moving_feature_share_mean", 1, 100),
                             Cell(report.spreads, pass, mode, "moving_feature_share_max", 1, 100)});
    }
  }
  return moving;
}

Table RunsTable(const ScenarioReport& report) {
  Table runs{"Every run", "Seeds are the simulated segmenter's; a deterministic mode ran once.",
             {"mode", "repeat", "seed", "pass1 ATE rmse [m]", "pass1 localized [%]", "pass2 ATE rmse [m]",
              "pass2 localized [%]", "seconds", "outputs"},
             {}};
  for (const RepeatRun& run : report.runs) {
    std::vector<std::string> row = {run.mode, std::to_string(run.repeat),
                                    report.bench.ModeIsDeterministic(run.mode) ? "-" : std::to_string(run.seed)};
    for (const auto& pass : kPasses) {
      double ate = kNaN, localized = kNaN;
      for (const PassEvaluation& p : run.evaluation.passes) {
        if (p.name != pass) continue;
        if (p.ate_m.has_value()) ate = p.ate_m->rmse;
        localized = p.LocalizedShare();
      }
      row.push_back(std::isnan(ate) ? "n/a" : fmt::format("{:.4f}", ate));
      row.push_back(std::isnan(localized) ? "n/a" : fmt::format("{:.1f}", 100 * localized));
    }
    row.push_back(fmt::format("{:.1f}", run.seconds));
    row.push_back(run.run_dir);
    runs.rows.push_back(row);
  }
  return runs;
}

std::vector<Table> ReportTables(const ScenarioReport& report) {
  std::vector<Table> tables;
  if (!report.checks.empty() || !report.not_checked.empty()) tables.push_back(ExpectationsTable(report));
  tables.push_back(AteTable(report));
  tables.push_back(RpeTable(report));
  tables.push_back(SegmentationTable(report));
  tables.push_back(RelocalizationTable(report));
  if (Table moving = MovingDetectionTable(report); !moving.rows.empty()) tables.push_back(std::move(moving));
  tables.push_back(RunsTable(report));
  return tables;
}

constexpr const char* kMaskFigureFile = "figures/masks_raw_vs_refined.png";
constexpr const char* kFeatureFigureFile = "figures/features_kept_vs_dropped.png";

// Pictures of the report, relative to the report directory, drawn by DrawReportFigures
// with harness/report_figures.h; the report shows each figure whose file exists (one
// that could not be drawn is missing, and `scenario run` says why).
struct PlannedFigure {
  std::string file;
  std::string caption;
};
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

// The planned figures whose files exist in the report directory.
std::vector<PlannedFigure> PresentFigures(const std::filesystem::path& report_dir) {
  std::vector<PlannedFigure> present;
  for (const PlannedFigure& figure : PlannedFigures()) {
    if (!report_dir.empty() && std::filesystem::exists(report_dir / figure.file)) present.push_back(figure);
  }
  return present;
}

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

std::string StemOf(const TumSequence& sequence, int frame) {
  return std::filesystem::path(sequence.entries()[static_cast<std::size_t>(frame)].rgb_file).stem().string();
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
    const std::string stem = StemOf(sequence, i);
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
  options.mode = slam::SlamMode::kMutual;
  if (report.bench.segmenter != "gt") options.segmenter = report.bench.segmenter;
  options.segmenter_seed = run.seed;
  options.segmenter_strength = report.bench.segmenter_strength;
  if (!options.segmenter.empty()) options.refiner = report.bench.LoopRefinerOptions();
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
  const std::string stem = StemOf(sequence, frame_index);
  const std::filesystem::path judged_masks =
      options.segmenter.empty() ? pass_dir / "masks" / (stem + ".png")
                                : report.report_dir / run.run_dir / "pass1" / "refined_masks" / (stem + ".png");
  const RgbdFrame frame = sequence.LoadFrame(*chosen);
  const std::string title =
      fmt::format("{} pass 1, frame {}, mutual{}", report.scenario_name, frame_index,
                  options.segmenter.empty() ? " on ground-truth masks" : fmt::format(" (seed {})", run.seed));
  WriteFigure(out, DrawFeatureKinds(frame.color_bgr, sequence.LoadInstanceMask(judged_masks), rerun.frames[*chosen], title));
}

std::string StatusLine(const ScenarioReport& report) {
  const auto passed = std::count_if(report.checks.begin(), report.checks.end(), [](const auto& c) { return c.passed; });
  std::string line = fmt::format("{} of {} expectations passed", passed, report.checks.size());
  if (!report.not_checked.empty()) line += fmt::format(", {} not checked", report.not_checked.size());
  return line;
}

// "name=value" for each leaf of a mapping of options. Nested mappings join their keys
// with '.', so `orb: {max_features: 1500}` (what --set bench.tracker.orb.max_features
// writes) and `orb.max_features: 1500` say the same.
void AppendOptionAssignments(const YAML::Node& options, const std::string& prefix, const std::string& where,
                             std::vector<std::string>* assignments) {
  if (!options.IsMap()) throw Error(where + ": expected a mapping of option: value");
  for (const auto& option : options) {
    const std::string name = prefix + option.first.Scalar();
    if (option.second.IsMap()) {
      AppendOptionAssignments(option.second, name + ".", where, assignments);
    } else if (option.second.IsScalar()) {
      assignments->push_back(name + "=" + option.second.Scalar());
    } else {
      throw Error(where + ": " + name + ": expected a number");
    }
  }
}

}  // namespace

BenchSettings BenchSettings::FromYaml(const YAML::Node& bench, const std::string& origin) {
  BenchSettings settings;
  if (!bench || bench.IsNull()) return settings;
  if (!bench.IsMap()) throw Error(origin + ": bench: expected a mapping");
  for (const auto& entry : bench) {
    const std::string key = entry.first.Scalar();
    const YAML::Node& value = entry.second;
    try {
      if (key == "modes") {
        settings.modes = value.IsSequence() ? value.as<std::vector<std::string>>() : Split(value.as<std::string>(), ',');
      } else if (key == "repeats") {
        settings.repeats = value.as<int>();
      } else if (key == "segmenter") {
        settings.segmenter = value.as<std::string>();
      } else if (key == "segmenter_strength") {
        settings.segmenter_strength = value.as<double>();
      } else if (key == "seed") {
        settings.seed = value.as<std::uint64_t>();
      } else if (key == "refiner") {
        AppendOptionAssignments(value, "", origin + ": bench.refiner", &settings.refiner);
      } else if (key == "tracker") {
        AppendOptionAssignments(value, "", origin + ": bench.tracker", &settings.tracker);
      } else {
        throw Error(origin + ": unknown key 'bench." + key +
                    "' (known: modes, repeats, segmenter, segmenter_strength, seed, refiner, tracker)");
      }
    } catch (const YAML::Exception& e) {
      throw Error(origin + ": bench." + key + ": " + e.msg);
    }
  }
  const std::string problem = settings.Check();
  if (!problem.empty()) throw Error(origin + ": bench: " + problem);
  return settings;
}

std::string BenchSettings::Check() const {
  if (modes.empty()) return "modes: at least one of plain, mask-moveable, mutual, oracle";
  std::set<std::string> seen;
  for (const std::string& mode : modes) {
    if (!Contains(slam::SlamModeNames(), mode)) return "modes: unknown mode '" + mode + "' (plain, mask-moveable, mutual or oracle)";
    if (!seen.insert(mode).second) return "modes: '" + mode + "' twice";
  }
  if (repeats < 1) return fmt::format("repeats: must be >= 1 (got {})", repeats);
  const std::vector<std::string> presets = seg::SimulatedSegmenterOptions::PresetNames();
  if (segmenter != "gt" && !Contains(presets, segmenter)) {
    return "segmenter: unknown '" + segmenter + "' (gt or " + Join(presets, ", ") + ")";
  }
  if (!(segmenter_strength >= 0 && segmenter_strength <= 10)) {
    return fmt::format("segmenter_strength: must be in [0, 10] (got {})", segmenter_strength);
  }
  if (segmenter == "gt" && segmenter_strength != 1.0) {
    return "segmenter_strength: scales a simulated segmenter's errors; ground-truth masks (gt) have none";
  }
  if (!refiner.empty()) {
    if (segmenter == "gt") return "refiner: the mutual loop refines a simulated segmenter's masks; ground-truth masks (gt) are not refined";
    try {
      std::string problem;
      if (!LoopRefinerOptions().IsValid(&problem)) return "refiner: " + problem;
    } catch (const Error& e) {
      return std::string("refiner: ") + e.what();
    }
  }
  try {
    TrackerOverrides();
  } catch (const Error& e) {
    return std::string("tracker: ") + e.what();
  }
  return "";
}

slam::TrackerOptions BenchSettings::TrackerOverrides() const {
  slam::TrackerOptions options;
  for (const std::string& assignment : tracker) slam::SetTrackerOption(&options, assignment);
  return options;
}

seg::RefinerOptions BenchSettings::LoopRefinerOptions() const {
  seg::RefinerOptions options;
  for (const std::string& assignment : refiner) seg::SetRefinerOption(&options, assignment);
  return options;
}

std::string BenchSettings::SegmenterLabel() const {
  return segmenter == "gt" ? segmenter : SimulatedSegmenterLabel(segmenter, segmenter_strength);
}

bool BenchSettings::ModeIsDeterministic(const std::string& mode) const {
  return mode == "plain" || mode == "oracle" || segmenter == "gt";
}

MetricName ParseMetricName(const std::string& text, const std::vector<std::string>& modes, const std::string& origin) {
  auto unknown = [&](const std::string& why) {
    return Error(origin + ": expect: unknown metric '" + PrintableText(text) + "': " + why +
                 " (names: [pass1.|pass2.]MODE.METRIC or [pass1.|pass2.]MODE_vs_MODE.METRIC_ratio, modes " +
                 Join(modes, ", ") + ")");
  };
  std::vector<std::string> parts = Split(text, '.');
  MetricName name;
  name.text = text;
  if (parts.size() == 3) {
    if (!Contains(kPasses, parts[0])) throw unknown("'" + parts[0] + "' is not pass1 or pass2");
    name.pass = parts[0];
    parts.erase(parts.begin());
  }
  if (parts.size() != 2) throw unknown("expected MODE.METRIC");
  const std::string& subject = parts[0];
  std::string metric = parts[1];
  const std::size_t vs = subject.find("_vs_");
  if (vs != std::string::npos) {
    name.mode = subject.substr(0, vs);
    name.denominator_mode = subject.substr(vs + 4);
    const std::string suffix = "_ratio";
    if (metric.size() <= suffix.size() || metric.compare(metric.size() - suffix.size(), suffix.size(), suffix) != 0) {
      throw unknown("a comparison of modes needs a METRIC_ratio, e.g. ate_ratio");
    }
    metric = metric.substr(0, metric.size() - suffix.size());
    if (metric == "ate") metric = "ate_rmse_m";
    if (!Contains(modes, name.denominator_mode)) throw unknown("mode '" + name.denominator_mode + "' does not run");
  } else {
    name.mode = subject;
  }
  if (!Contains(modes, name.mode)) throw unknown("mode '" + name.mode + "' does not run");
  if (!Contains(PassMetricNames(), metric)) {
    throw unknown("'" + metric + "' is not one of " + Join(PassMetricNames(), ", "));
  }
  name.metric = metric;
  return name;
}

std::string Expectation::Bounds() const {
  if (min.has_value() && max.has_value()) return fmt::format("in [{:g}, {:g}]", *min, *max);
  if (min.has_value()) return fmt::format(">= {:g}", *min);
  return fmt::format("<= {:g}", *max);
}

std::vector<Expectation> ParseExpectations(const YAML::Node& expect, const std::vector<std::string>& modes,
                                           const std::string& origin) {
  std::vector<Expectation> expectations;
  if (!expect || expect.IsNull()) return expectations;
  if (!expect.IsMap()) throw Error(origin + ": expect: expected a mapping of metric: {min: X, max: Y}");
  for (const auto& entry : expect) {
    const std::string text = entry.first.Scalar();
    Expectation expectation;
    expectation.name = ParseMetricName(text, modes, origin);
    if (!entry.second.IsMap() || entry.second.size() == 0) {
      throw Error(origin + ": expect: " + text + ": expected {min: X}, {max: X} or both");
    }
    for (const auto& bound : entry.second) {
      const std::string key = bound.first.Scalar();
      double value = 0;
      try {
        value = bound.second.as<double>();
      } catch (const YAML::Exception&) {
        throw Error(origin + ": expect: " + text + "." + key + ": expected a number");
      }
      if (!std::isfinite(value)) throw Error(origin + ": expect: " + text + "." + key + ": expected a finite number");
      if (key == "min") {
        expectation.min = value;
      } else if (key == "max") {
        expectation.max = value;
      } else {
        throw Error(origin + ": expect: " + text + ": unknown bound '" + key + "' (min or max)");
      }
    }
    expectations.push_back(expectation);
  }
  return expectations;
}

Spread SpreadOf(std::vector<double> values) {
  Spread spread;
  spread.runs = static_cast<int>(values.size());
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return std::isnan(v); }), values.end());
  spread.count = static_cast<int>(values.size());
  if (values.empty()) {
    spread.median = spread.min = spread.max = kNaN;
    return spread;
  }
  spread.median = Median(values);
  spread.min = *std::min_element(values.begin(), values.end());
  spread.max = *std::max_element(values.begin(), values.end());
  return spread;
}

SpreadTable Summarize(const std::vector<RepeatRun>& runs) {
  std::map<std::string, std::map<std::string, std::map<std::string, std::vector<double>>>> values;
  for (const RepeatRun& run : runs) {
    for (const PassEvaluation& pass : run.evaluation.passes) {
      for (const auto& [metric, value] : PassMetrics(pass)) values[pass.name][run.mode][metric].push_back(value);
    }
  }
  SpreadTable table;
  for (const auto& [pass, modes] : values) {
    for (const auto& [mode, metrics] : modes) {
      for (const auto& [metric, list] : metrics) table[pass][mode][metric] = SpreadOf(list);
    }
  }
  return table;
}

std::vector<ExpectationResult> CheckExpectations(const std::vector<Expectation>& expectations, const SpreadTable& table) {
  std::vector<ExpectationResult> results;
  for (const Expectation& expectation : expectations) {
    const MetricName& name = expectation.name;
    // A run without the value (no ATE after a pass that lost its map, say) fails the
    // check: the median of the others would hide it.
    auto median = [&](const std::string& mode) {
      const Spread* s = FindSpread(table, name.pass, mode, name.metric);
      return s == nullptr || s->count < s->runs ? kNaN : s->median;
    };
    ExpectationResult result;
    result.expectation = expectation;
    result.value = name.IsRatio() ? median(name.mode) / median(name.denominator_mode) : median(name.mode);
    result.passed = std::isfinite(result.value) && (!expectation.min || result.value >= *expectation.min) &&
                    (!expectation.max || result.value <= *expectation.max);
    results.push_back(result);
  }
  return results;
}

std::vector<std::string> ModesThatRan(const std::vector<nlohmann::json>& results) {
  std::vector<std::string> modes;
  for (const std::string& mode : slam::SlamModeNames()) {
    for (const nlohmann::json& r : results) {
      const nlohmann::json ran = r.contains("bench") ? r["bench"].value("modes", nlohmann::json::array())
                                                     : nlohmann::json::array();
      if (std::find(ran.begin(), ran.end(), mode) != ran.end()) {
        modes.push_back(mode);
        break;
      }
    }
  }
  return modes;
}

nlohmann::json ScenarioReport::ToJson() const {
  nlohmann::json json = {
      {"scenario", scenario_name},
      {"scenario_file", scenario_file},
      {"scenario_effective", effective_scenario_yaml},
      {"overrides", overrides},
      {"code_version", code_version},
      {"machine", MachineDescription()},
      {"dataset", dataset_dir},
      {"dataset_from_cache", dataset_from_cache},
      {"dataset_movers_left_out", movers_left_out},
      {"dataset_red_lights_left_out", red_lights_left_out},
      {"frames_per_pass", frames_per_pass},
      {"bench",
       {{"modes", bench.modes}, {"repeats", bench.repeats}, {"segmenter", bench.segmenter},
        {"segmenter_strength", bench.segmenter_strength}, {"seed", bench.seed}, {"refiner", bench.refiner},
        {"tracker", bench.tracker}}},
      {"seconds", seconds},
      {"runs", nlohmann::json::array()},
      {"summary", nlohmann::json::object()},
      {"expectations", nlohmann::json::array()},
      {"expectations_not_checked", not_checked},
      {"passed", Passed()}};
  for (const std::string& mode : bench.modes) {
    json["bench"]["deterministic"][mode] = bench.ModeIsDeterministic(mode);
  }
  for (const RepeatRun& run : runs) {
    nlohmann::json entry = {{"mode", run.mode},       {"repeat", run.repeat},
                            {"seed", bench.ModeIsDeterministic(run.mode) ? nlohmann::json(nullptr) : nlohmann::json(run.seed)},
                            {"run_dir", run.run_dir}, {"seconds", run.seconds},
                            {"evaluation", run.evaluation.ToJson()}};
    json["runs"].push_back(entry);
  }
  for (const auto& [pass, modes] : spreads) {
    for (const auto& [mode, metrics] : modes) {
      for (const auto& [metric, s] : metrics) {
        json["summary"][pass][mode][metric] = {{"runs", s.runs}, {"count", s.count}, {"median", NumberJson(s.median)},
                                               {"min", NumberJson(s.min)}, {"max", NumberJson(s.max)}};
      }
    }
  }
  for (const ExpectationResult& r : checks) {
    json["expectations"].push_back({{"metric", r.expectation.name.text},
                                    {"min", r.expectation.min ? nlohmann::json(*r.expectation.min) : nlohmann::json(nullptr)},
                                    {"max", r.expectation.max ? nlohmann::json(*r.expectation.max) : nlohmann::json(nullptr)},
                                    {"value", NumberJson(r.value)},
                                    {"passed", r.passed}});
  }
  return json;
}

ReportDocument ScenarioReport::ToDocument() const {
  ReportDocument document("segslam scenario report: " + scenario_name);
  document.AddMetadata("scenario file", scenario_file + (overrides.empty() ? "" : ", overrides " + Join(overrides, " ")));
  document.AddMetadata("code version", code_version);
  document.AddMetadata("machine", MachineLine(MachineDescription()));
  document.AddMetadata("dataset", dataset_dir + (dataset_from_cache ? " (from the cache)" : "") +
                                      (frames_per_pass > 0 ? fmt::format(", first {} frames per pass", frames_per_pass) : "") +
                                      (movers_left_out > 0 ? fmt::format(", {} of the scenario's moving cars and pedestrians "
                                                                         "left out (no path clear of the others)",
                                                                         movers_left_out)
                                                           : "") +
                                      (red_lights_left_out > 0
                                           ? fmt::format(", {} of the scenario's red lights left out (too few "
                                                         "intersections, or too near to brake for)",
                                                         red_lights_left_out)
                                           : ""));
  const bool oracle = std::find(bench.modes.begin(), bench.modes.end(), "oracle") != bench.modes.end();
  document.AddMetadata("bench", fmt::format("modes {}, {} repeat(s), segmenter {} with seeds {}..{}; deterministic modes "
                                            "ran once{}",
                                            Join(bench.modes, ", "), bench.repeats, bench.SegmenterLabel(), bench.seed,
                                            bench.seed + static_cast<std::uint64_t>(bench.repeats) - 1,
                                            oracle ? "; oracle: mutual with the ground truth's masks and moving/static "
                                                     "verdicts, for reference"
                                                   : ""));
  if (!bench.refiner.empty()) document.AddMetadata("refiner", "the mutual loop's, with " + Join(bench.refiner, " "));
  if (!bench.tracker.empty()) document.AddMetadata("tracker", "every mode's, with " + Join(bench.tracker, " "));
  document.AddMetadata("result", fmt::format("{} in {:.1f} s", StatusLine(*this), seconds));
  for (const Table& table : ReportTables(*this)) {
    document.AddHeading(table.title, 3);
    if (!table.note.empty()) document.AddParagraph(table.note);
    document.AddTable(ReportTable{"", table.header, table.rows});
  }
  document.AddHeading("Figures", 3);
  const std::vector<PlannedFigure> figures = PresentFigures(report_dir);
  for (const PlannedFigure& figure : figures) document.AddImage(figure.file, figure.caption);
  if (figures.empty()) document.AddParagraph("None drawn.");
  document.AddHeading("Effective scenario", 3);
  document.AddParagraph("scenario.yaml beside this report holds every key of the scenario that ran, defaults and "
                        "--set overrides included (also in results.json).");
  return document;
}

std::string ScenarioReport::ToMarkdown() const { return ToDocument().ToMarkdown(); }

std::string ScenarioReport::ToText() const {
  std::string text;
  for (const Table& table : ReportTables(*this)) {
    std::vector<std::size_t> widths(table.header.size(), 0);
    for (std::size_t c = 0; c < table.header.size(); ++c) widths[c] = table.header[c].size();
    for (const auto& row : table.rows) {
      for (std::size_t c = 0; c < row.size() && c < widths.size(); ++c) widths[c] = std::max(widths[c], row[c].size());
    }
    auto line = [&](const std::vector<std::string>& cells) {
      std::string out;
      for (std::size_t c = 0; c < cells.size() && c < widths.size(); ++c) {
        // The first column names the row; numbers read best right-aligned.
        out += c == 0 ? fmt::format("{:<{}}", cells[c], widths[c]) : fmt::format("  {:>{}}", cells[c], widths[c]);
      }
      return out + "\n";
    };
    text += "\n" + table.title + "\n" + line(table.header);
    for (const auto& row : table.rows) text += line(row);
    if (!table.note.empty()) text += "(" + table.note + ")\n";
  }
  return text;
}

std::string ScenarioReport::ToHtml() const { return ToDocument().ToHtml(); }

std::vector<std::string> DrawReportFigures(const ScenarioReport& report) {
  std::vector<std::string> problems;
  for (const std::string& pass : kPasses) {
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

bool ScenarioReport::Passed() const {
  const bool all_passed = std::all_of(checks.begin(), checks.end(), [](const auto& c) { return c.passed; });
  return all_passed && !(checks.empty() && !not_checked.empty());
}

std::string ScenarioReport::ToJUnitXml() const {
  // A run that checked none of its expectations fails as a testcase of its own, so that a
  // CI reading the XML sees what the exit code says.
  const bool nothing_checked = checks.empty() && !not_checked.empty();
  const auto failures =
      std::count_if(checks.begin(), checks.end(), [](const auto& c) { return !c.passed; }) + (nothing_checked ? 1 : 0);
  std::string text = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  text += fmt::format(
      "<testsuites>\n<testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"0\" skipped=\"{}\" time=\"{:.3f}\">\n",
      EscapeXml("segslam scenario " + scenario_name), checks.size() + not_checked.size() + (nothing_checked ? 1 : 0),
      failures, not_checked.size(), seconds);
  if (nothing_checked) {
    text += fmt::format(
        "  <testcase classname=\"{}\" name=\"no expectation checked\" time=\"0\"><failure message=\"{}\"/></testcase>\n",
        EscapeXml("segslam.scenario." + scenario_name),
        EscapeXml("--modes leaves out a mode of every expectation of the scenario"));
  }
  for (const ExpectationResult& r : checks) {
    text += fmt::format("  <testcase classname=\"{}\" name=\"{}\" time=\"0\">",
                        EscapeXml("segslam.scenario." + scenario_name),
                        EscapeXml(r.expectation.name.text + " " + r.expectation.Bounds()));
    if (!r.passed) {
      text += fmt::format("<failure message=\"{}\"/>",
                          EscapeXml(fmt::format("median over repeats {} not {}", ValueText(r.value), r.expectation.Bounds())));
    }
    text += "</testcase>\n";
  }
  for (const std::string& name : not_checked) {
    text += fmt::format("  <testcase classname=\"{}\" name=\"{}\" time=\"0\"><skipped message=\"{}\"/></testcase>\n",
                        EscapeXml("segslam.scenario." + scenario_name), EscapeXml(name),
                        EscapeXml("--modes leaves its mode out"));
  }
  return text + "</testsuite>\n</testsuites>\n";
}

}  // namespace segslam::harness
