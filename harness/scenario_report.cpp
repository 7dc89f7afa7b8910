// ScenarioReport (harness/scenario_report.h): the paper's tables from the spreads over
// repeats, results.json, report.md and report.html, the terminal's text and JUnit XML.
#include "harness/scenario_report.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "core/strings.h"
#include "harness/machine.h"
#include "harness/map_relative_error.h"
#include "harness/run_evaluation.h"
#include "harness/scenario_figures.h"
#include "mutual/slam_mode.h"
#include "seg/refiner_options.h"
#include "slam/tracker_options.h"

namespace segslam::harness {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

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
  for (const auto& pass : kScenarioPasses) {
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
  for (const auto& pass : kScenarioPasses) {
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
  for (const auto& pass : kScenarioPasses) {
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

// With the static twin: per pass and mode, the share of the traffic's added error the
// mode removes, beside its ATE and its ratio to plain.
Table StaticTwinTable(const ScenarioReport& report) {
  Table table{"The static twin: the share of the traffic's added error each mode removes",
              "ATE rmse as above (median over repeats). Plain on the static twin is plain on the same world "
              "with nothing moving through it (" +
                  report.static_twin_dataset_dir +
                  "). Removed: (plain - mode) / (plain - plain on the static twin); 100 % is as good as plain "
                  "with nothing moving, 0 % as bad as plain among the traffic; n/a where the traffic adds no "
                  "error to plain.",
              {"sequence", "plain on the static twin [m]", "mode", "ATE rmse [m]", "ratio to plain", "removed [%]"},
              {}};
  for (const auto& pass : kScenarioPasses) {
    const Spread* twin = FindSpread(report.spreads, pass, kStaticTwinPlain, "ate_rmse_m");
    const Spread* plain = FindSpread(report.spreads, pass, "plain", "ate_rmse_m");
    for (const std::string& mode : report.bench.modes) {
      const Spread* ate = FindSpread(report.spreads, pass, mode, "ate_rmse_m");
      const double ratio = ate != nullptr && plain != nullptr ? ate->median / plain->median : kNaN;
      const double removed = TrafficErrorRemoved(report.spreads, pass, mode);
      table.rows.push_back({report.scenario_name + " " + pass, twin == nullptr ? "n/a" : SpreadText(*twin, 4), mode,
                            Cell(report.spreads, pass, mode, "ate_rmse_m", 4),
                            std::isnan(ratio) ? "n/a" : fmt::format("{:.2f}", ratio),
                            std::isnan(removed) ? "n/a" : fmt::format("{:.0f}", 100 * removed)});
    }
  }
  return table;
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
  for (const auto& pass : kScenarioPasses) {
    for (const auto& mode : report.bench.modes) {
      if (mode != "mutual" && mode != "mutual-sparse") continue;
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

// Where the judgement misses (the judging modes but the oracle): coverage and precision by
// distance band and by class, per pass and mode.
Table MovingBreakdownTable(const ScenarioReport& report) {
  Table table{"Moving-object detection by distance and class [%]",
              std::string(kSpreadNote) +
                  " Coverage and precision as above, of the (frame, instance) pairs whose ground-truth object "
                  "lies in that band of distance from the camera (its tracks.json pose) or is of that class; n/a: "
                  "none seen moving (coverage) or none judged moving (precision). mutual judges from the depth of "
                  "each instance's pixels, mutual-sparse from re-found sparse features, as the paper.",
              {"objects"},
              {}};
  std::vector<std::string> judging;
  for (const std::string& mode : report.bench.modes) {
    if (mode == "mutual" || mode == "mutual-sparse") judging.push_back(mode);
  }
  if (judging.empty()) return table;
  for (const auto& pass : kScenarioPasses) {
    for (const std::string& mode : judging) {
      const std::string suffix = judging.size() > 1 ? " (" + mode + ")" : "";
      table.header.push_back(std::string(pass) + " coverage" + suffix);
      table.header.push_back(std::string(pass) + " precision" + suffix);
    }
  }
  const auto add_row = [&](const std::string& label, const std::string& group) {
    std::vector<std::string> row = {label};
    for (const auto& pass : kScenarioPasses) {
      for (const std::string& mode : judging) {
        row.push_back(Cell(report.spreads, pass, mode, "moving_coverage_" + group, 1, 100));
        row.push_back(Cell(report.spreads, pass, mode, "moving_precision_" + group, 1, 100));
      }
    }
    table.rows.push_back(row);
  };
  const std::vector<std::string> band_labels = {"0 to 10 m", "10 to 20 m", "20 to 40 m", "40 m and more"};
  for (std::size_t b = 0; b < MovingDistanceBands().size(); ++b) add_row(band_labels[b], MovingDistanceBands()[b]);
  for (const std::string& name : MovingClasses()) add_row(name, name);
  return table;
}

Table RunsTable(const ScenarioReport& report) {
  Table runs{"Every run",
             "Seeds are the simulated segmenter's; a deterministic mode ran once. ORB features: the "
             "tracker's feature budget (repeats differ in it when bench.feature_jitter is set).",
             {"mode", "repeat", "seed", "ORB features", "pass1 ATE rmse [m]", "pass1 localized [%]",
              "pass2 ATE rmse [m]", "pass2 localized [%]", "seconds", "outputs"},
             {}};
  for (const RepeatRun& run : report.runs) {
    std::vector<std::string> row = {run.mode, std::to_string(run.repeat),
                                    report.bench.ModeIsDeterministic(run.mode) ? "-" : std::to_string(run.seed),
                                    std::to_string(report.bench.FeatureBudgetFor(run.repeat))};
    for (const auto& pass : kScenarioPasses) {
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
  if (!report.static_twin_runs.empty()) tables.push_back(StaticTwinTable(report));
  if (Table moving = MovingDetectionTable(report); !moving.rows.empty()) tables.push_back(std::move(moving));
  if (Table breakdown = MovingBreakdownTable(report); !breakdown.rows.empty()) tables.push_back(std::move(breakdown));
  tables.push_back(RunsTable(report));
  return tables;
}

std::string StatusLine(const ScenarioReport& report) {
  const auto passed = std::count_if(report.checks.begin(), report.checks.end(), [](const auto& c) { return c.passed; });
  std::string line = fmt::format("{} of {} expectations passed", passed, report.checks.size());
  if (!report.not_checked.empty()) line += fmt::format(", {} not checked", report.not_checked.size());
  return line;
}

}  // namespace

std::vector<std::string> ModesThatRan(const std::vector<nlohmann::json>& results) {
  std::vector<std::string> modes;
  for (const std::string& mode : mutual::SlamModeNames()) {
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
        {"tracker", bench.tracker}, {"static_twin", bench.static_twin}, {"feature_jitter", bench.feature_jitter}}},
      {"options",
       {{"tracker", slam::TrackerOptionRegistry().ToJson(bench.TrackerOverrides())},
        {"refiner", seg::RefinerOptionRegistry().ToJson(bench.LoopRefinerOptions())}}},
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
                            {"orb_max_features", bench.FeatureBudgetFor(run.repeat)},
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
  if (!static_twin_runs.empty()) {
    nlohmann::json twin = {{"dataset", static_twin_dataset_dir}, {"runs", nlohmann::json::array()}};
    for (const RepeatRun& run : static_twin_runs) {
      twin["runs"].push_back({{"mode", run.mode}, {"repeat", run.repeat},
                              {"orb_max_features", bench.FeatureBudgetFor(run.repeat)},
                              {"run_dir", run.run_dir}, {"seconds", run.seconds},
                              {"evaluation", run.evaluation.ToJson()}});
    }
    for (const auto& pass : kScenarioPasses) {
      for (const std::string& mode : bench.modes) {
        twin[kTrafficErrorRemoved][pass][mode] = NumberJson(TrafficErrorRemoved(spreads, pass, mode));
      }
    }
    json["static_twin"] = twin;
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

namespace {

// Name, value (starred where it is not the default), range and unit of every option.
template <typename Options>
ReportTable OptionsTable(const OptionRegistry<Options>& registry, const Options& used, const std::string& what) {
  const Options defaults;
  ReportTable table{what + " options", {"option", "value", "range"}, {}};
  for (const auto& spec : registry.specs()) {
    const double value = spec.get(used);
    table.rows.push_back({spec.name, FormatOptionValue(value) + (value != spec.get(defaults) ? " *" : ""),
                          registry.RangeText(spec)});
  }
  return table;
}

}  // namespace

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
  document.AddHeading("Effective options", 3);
  document.AddParagraph("Every tunable of the tracker (every mode) and of the mutual loop's mask refinement as these "
                        "runs used them (results.json: options); * marks a value the bench: section set. "
                        "`segslam options tracker` and `segslam options refiner` say what each does.");
  document.AddTable(OptionsTable(slam::TrackerOptionRegistry(), bench.TrackerOverrides(), "tracker"));
  document.AddTable(OptionsTable(seg::RefinerOptionRegistry(), bench.LoopRefinerOptions(), "refiner"));
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
