// The scores of a scenario's repeated runs summarized, and the scenario's `expect:`
// thresholds checked on those summaries: the names of metrics that thresholds refer to,
// the thresholds, the runs, and the median, min and max of each metric over repeats.
//
// Metric names (used by `expect:`, results.json and the reports):
//   [PASS.]MODE.METRIC              the median over repeats of METRIC of MODE's runs
//   [PASS.]MODE_A_vs_MODE_B.RATIO   median(A's METRIC) / median(B's METRIC)
// PASS is pass1 or pass2 and defaults to pass1; MODE is plain, mask-moveable or mutual
// and must be one of the modes that run; METRIC is one of PassMetricNames()
// (harness/run_evaluation.h: ate_rmse_m, localized_share, seg_refined_map, ...); RATIO is
// METRIC + "_ratio", or ate_ratio for ate_rmse_m_ratio (the paper's headline figure).
// Examples: mutual.ate_rmse_m, pass2.mutual.localized_share, mutual_vs_plain.ate_ratio.
//   [PASS.]MODE.traffic_error_removed   with the static twin (bench: {static_twin: true}):
//                                       the share of the traffic's added error MODE
//                                       removes, TrafficErrorRemoved().
// A threshold is {min: X}, {max: X} or both; a value that is NaN (the metric does not
// exist for that mode, e.g. seg_refined_map of plain) fails.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "harness/run_evaluation.h"

namespace segslam::harness {

// The passes of a scenario's dataset, as metric names, results.json and reports name them.
inline const std::vector<std::string> kScenarioPasses = {"pass1", "pass2"};

// Plain on the scenario's static twin (scenes::StaticTwin), as the spread table and
// results.json name it beside the modes.
inline const std::string kStaticTwinPlain = "plain-static-twin";
inline const std::string kTrafficErrorRemoved = "traffic_error_removed";

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

// Per pass, per mode, per metric: the spread over repeats.
using SpreadTable = std::map<std::string, std::map<std::string, std::map<std::string, Spread>>>;
SpreadTable Summarize(const std::vector<RepeatRun>& runs);

// The spread of `metric` of `mode` on `pass`; nullptr where the table has none.
const Spread* FindSpread(const SpreadTable& table, const std::string& pass, const std::string& mode,
                         const std::string& metric);

// The share of the error that the scenario's traffic adds to plain which `mode` removes,
// from the medians of ate_rmse_m on `pass`: (plain - mode) / (plain - plain on the static
// twin). 1: the mode does as well as plain with nothing moving; 0: as badly as plain; NaN
// without the twin's figure, a run without a value, or no added error to remove.
double TrafficErrorRemoved(const SpreadTable& table, const std::string& pass, const std::string& mode);

struct ExpectationResult {
  Expectation expectation;
  double value = 0;  // NaN when the metric has no value
  bool passed = false;
};

// Each expectation's value, the median over repeats (ratios: of medians), against its
// bounds. A mode with a run that lacks the value fails: the others' median would hide it.
std::vector<ExpectationResult> CheckExpectations(const std::vector<Expectation>& expectations, const SpreadTable& table);

}  // namespace segslam::harness
