// What `segslam scenario run` needs besides running: its settings (the scenario's
// `bench:` section), the names of metrics that `expect:` thresholds refer to, the
// aggregation of repeated runs (median, min, max) and the report files (results.json,
// report.md, report.html, JUnit XML).
//
// Metric names (used by `expect:`, results.json and the reports):
//   [PASS.]MODE.METRIC              the median over repeats of METRIC of MODE's runs
//   [PASS.]MODE_A_vs_MODE_B.RATIO   median(A's METRIC) / median(B's METRIC)
// PASS is pass1 or pass2 and defaults to pass1; MODE is plain, mask-moveable or mutual
// and must be one of the modes that run; METRIC is one of PassMetricNames()
// (harness/run_evaluation.h: ate_rmse_m, localized_share, seg_refined_map, ...); RATIO is
// METRIC + "_ratio", or ate_ratio for ate_rmse_m_ratio (the paper's headline figure).
// Examples: mutual.ate_rmse_m, pass2.mutual.localized_share, mutual_vs_plain.ate_ratio.
// A threshold is {min: X}, {max: X} or both; a value that is NaN (the metric does not
// exist for that mode, e.g. seg_refined_map of plain) fails.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "harness/report_document.h"
#include "harness/run_evaluation.h"
#include "seg/refiner.h"
#include "slam/tracker.h"

namespace segslam::harness {

// The scenario's `bench:` section; command-line options override it.
struct BenchSettings {
  std::vector<std::string> modes = slam::PaperModeNames();  // the oracle only when named
  int repeats = 10;  // runs per mode, differing by the segmenter's seed (the paper: 10)
  // Simulated segmenter preset (seg/simulated_segmenter.h) for mask-moveable and mutual;
  // "gt" uses the dataset's ground-truth masks (then every mode is deterministic).
  std::string segmenter = "fcis-like";
  // Scales every error of the simulated segmenter: 0 = ground truth, 1 = the preset, 2 =
  // twice as bad; a sweep axis for segmentation error strength. [0, 10].
  double segmenter_strength = 1.0;
  std::uint64_t seed = 1;  // repeat r (0-based) uses seed + r
  // "name=value" overrides of the mutual loop's refinement (seg/refiner_option_overrides.h),
  // from `refiner: {name: value, ...}`; a sweep axis as bench.refiner.NAME. Only the loop
  // refines, so they need a simulated segmenter.
  std::vector<std::string> refiner;
  // "name=value" overrides of the tracker (slam/tracker_option_overrides.h) in every
  // mode, from `tracker: {name: value, ...}`; nested names as orb: {max_features: 1500}
  // or orb.max_features. A sweep axis as bench.tracker.NAME.
  std::vector<std::string> tracker;

  // Throws segslam::Error naming `origin` and the key on unknown keys or bad values.
  static BenchSettings FromYaml(const YAML::Node& bench, const std::string& origin);
  // Empty when valid, else what is wrong.
  std::string Check() const;
  // Without a simulated segmenter SLAM is deterministic: one run says everything.
  bool ModeIsDeterministic(const std::string& mode) const;
  // The segmenter as reports name it: "gt", "fcis-like", "fcis-like@2".
  std::string SegmenterLabel() const;
  // The refinement options of the mutual loop: the defaults with `refiner` set.
  seg::RefinerOptions LoopRefinerOptions() const;
  // The tracker's options: the defaults with `tracker` set.
  slam::TrackerOptions TrackerOverrides() const;
};

struct MetricName {
  std::string text;  // as written
  std::string pass = "pass1";
  std::string mode;
  std::string denominator_mode;  // set for a ratio
  std::string metric;            // a PassMetricNames() entry
  bool IsRatio() const { return !denominator_mode.empty(); }
};

// Throws segslam::Error "<origin>: expect: unknown metric '<text>' (...)" when the name
// does not follow the scheme or names a mode that is not in `modes`.
MetricName ParseMetricName(const std::string& text, const std::vector<std::string>& modes, const std::string& origin);

struct Expectation {
  MetricName name;
  std::optional<double> min, max;
  std::string Bounds() const;  // "<= 0.05", ">= 0.95", "in [a, b]"
};

// Parses the `expect:` map; every error (unknown metric, bad bound) is thrown before any
// work starts.
std::vector<Expectation> ParseExpectations(const YAML::Node& expect, const std::vector<std::string>& modes,
                                           const std::string& origin);

// One run of one mode (both passes).
struct RepeatRun {
  std::string mode;
  int repeat = 0;
  std::uint64_t seed = 0;  // the segmenter's; meaningless for a deterministic mode
  std::string run_dir;     // relative to the report directory
  double seconds = 0;
  RunEvaluation evaluation;
};

struct Spread {
  int runs = 0;   // runs summarized
  int count = 0;  // of which with a value (not NaN)
  double median = 0, min = 0, max = 0;  // NaN when count is 0
};

// Median (numpy's: mean of the two middle values for an even count), min and max of the
// values that are not NaN.
Spread SpreadOf(std::vector<double> values);

struct ExpectationResult {
  Expectation expectation;
  double value = 0;  // NaN when the metric has no value
  bool passed = false;
};

// Per pass, per mode, per metric: the spread over repeats.
using SpreadTable = std::map<std::string, std::map<std::string, std::map<std::string, Spread>>>;
SpreadTable Summarize(const std::vector<RepeatRun>& runs);

std::vector<ExpectationResult> CheckExpectations(const std::vector<Expectation>& expectations, const SpreadTable& table);


struct ScenarioReport {
  std::string scenario_name;
  std::string scenario_file;
  std::string effective_scenario_yaml;  // scenes::ScenarioToYaml, what ran
  std::vector<std::string> overrides;   // --set
  std::string code_version;             // git describe at configure time
  std::string dataset_dir;
  bool dataset_from_cache = false;
  int movers_left_out = 0;  // the dataset's moving actors without a clear path (manifest.json)
  int red_lights_left_out = 0;  // the scenario's red lights the route had no room for (manifest.json)
  int frames_per_pass = 0;  // --frames; 0 = the scenario's own
  BenchSettings bench;
  std::vector<RepeatRun> runs;
  SpreadTable spreads;
  std::vector<ExpectationResult> checks;
  // The scenario's expectations this run could not check (--modes left a mode out).
  std::vector<std::string> not_checked;
  double seconds = 0;
  std::filesystem::path report_dir;  // where figures are looked for (not written out)

  // Every checked expectation passed, and at least one was checked where the scenario
  // has any: a run whose --modes leaves every expectation out verified nothing.
  bool Passed() const;
  nlohmann::json ToJson() const;
  // The tables (and the figures present in report_dir) as one document.
  ReportDocument ToDocument() const;
  std::string ToMarkdown() const;
  // The report's tables as aligned plain text, for the terminal.
  std::string ToText() const;
  std::string ToHtml() const;
  // One testcase per expectation.
  std::string ToJUnitXml() const;
};

// The modes, in the paper's order (slam::SlamModeNames), that ran in any of these
// results.json documents (ScenarioReport::ToJson); one without a bench section ran none.
std::vector<std::string> ModesThatRan(const std::vector<nlohmann::json>& results);

// Draws the report's figures into report.report_dir/figures/: top views of both passes
// (as the paper's Fig. 4), and for one frame of pass 1 of the mutual run of median ATE
// the raw vs refined masks (Fig. 5) and the features kept vs dropped (Fig. 6; this runs
// that pass again with feature records, as they are not saved). A figure that cannot be
// drawn (e.g. the mutual mode did not run) is skipped; the returned lines say which and
// why.
std::vector<std::string> DrawReportFigures(const ScenarioReport& report);

}  // namespace segslam::harness
