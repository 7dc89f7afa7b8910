// The metric names of `expect:`, the median over repeats and the threshold checks.
#include "harness/scenario_report.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/error.h"
#include "slam/tracker_options.h"

namespace segslam::harness {
namespace {

const std::vector<std::string> kModes = {"plain", "mask-moveable", "mutual"};

std::string ParseError(const std::string& text, const std::vector<std::string>& modes = kModes) {
  try {
    ParseMetricName(text, modes, "s.yaml");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ScenarioReportTest, MetricNamesFollowTheScheme) {
  MetricName name = ParseMetricName("mutual.ate_rmse_m", kModes, "s.yaml");
  EXPECT_EQ(name.pass, "pass1");
  EXPECT_EQ(name.mode, "mutual");
  EXPECT_EQ(name.metric, "ate_rmse_m");
  EXPECT_FALSE(name.IsRatio());

  name = ParseMetricName("pass2.mutual.localized_share", kModes, "s.yaml");
  EXPECT_EQ(name.pass, "pass2");
  EXPECT_EQ(name.metric, "localized_share");

  name = ParseMetricName("mutual_vs_plain.ate_ratio", kModes, "s.yaml");
  EXPECT_EQ(name.mode, "mutual");
  EXPECT_EQ(name.denominator_mode, "plain");
  EXPECT_EQ(name.metric, "ate_rmse_m");

  name = ParseMetricName("pass2.mask-moveable_vs_plain.rpe_trans_rmse_m_ratio", kModes, "s.yaml");
  EXPECT_EQ(name.mode, "mask-moveable");
  EXPECT_EQ(name.metric, "rpe_trans_rmse_m");
}

// Pass 2's map-relative relocalization error (harness/map_relative_error.h) is a metric
// like any other, and Table III shows it beside the ATE in the map frame.
TEST(ScenarioReportTest, MapRelativeErrorIsAMetricAndInTableThree) {
  const MetricName within = ParseMetricName("pass2.mutual.reloc_within_share", kModes, "s.yaml");
  EXPECT_EQ(within.pass, "pass2");
  EXPECT_EQ(within.metric, "reloc_within_share");
  EXPECT_EQ(ParseMetricName("pass2.mutual_vs_plain.reloc_trans_rmse_m_ratio", kModes, "s.yaml").metric,
            "reloc_trans_rmse_m");
  EXPECT_EQ(ParseMetricName("pass2.mutual.reloc_rot_rmse_deg", kModes, "s.yaml").metric, "reloc_rot_rmse_deg");

  ScenarioReport report;
  report.scenario_name = "route";
  report.bench.modes = {"plain", "mutual"};
  report.spreads["pass2"]["mutual"]["ate_rmse_m"] = SpreadOf({0.5});
  report.spreads["pass2"]["mutual"]["reloc_trans_rmse_m"] = SpreadOf({0.0123});
  report.spreads["pass2"]["mutual"]["reloc_rot_rmse_deg"] = SpreadOf({0.456});
  report.spreads["pass2"]["mutual"]["reloc_within_share"] = SpreadOf({0.875});
  const std::string markdown = report.ToMarkdown();
  const std::size_t table = markdown.find("Relocalization in pass 2");
  ASSERT_NE(table, std::string::npos) << markdown;
  EXPECT_NE(markdown.find("map-relative rmse", table), std::string::npos) << markdown.substr(table);
  EXPECT_NE(markdown.find("| mutual | n/a | 0.5000 | n/a | 0.0123 | 0.456 | 87.5 |", table), std::string::npos)
      << markdown.substr(table);
}

TEST(ScenarioReportTest, UnknownMetricNamesAreRefused) {
  EXPECT_NE(ParseError("mutual.ate").find("s.yaml: expect: unknown metric 'mutual.ate'"), std::string::npos);
  EXPECT_NE(ParseError("pass3.mutual.ate_rmse_m").find("'pass3' is not pass1 or pass2"), std::string::npos);
  EXPECT_NE(ParseError("mutual_vs_plain.ate_rmse_m").find("METRIC_ratio"), std::string::npos);
  EXPECT_NE(ParseError("slow.ate_rmse_m").find("mode 'slow' does not run"), std::string::npos);
  EXPECT_NE(ParseError("mutual.ate_rmse_m", {"plain"}).find("mode 'mutual' does not run"), std::string::npos);
  EXPECT_NE(ParseError("ate_rmse_m").find("expected MODE.METRIC"), std::string::npos);
}

TEST(ScenarioReportTest, BoundsAreChecked) {
  const YAML::Node bad = YAML::Load("{mutual.ate_rmse_m: {below: 1}}");
  EXPECT_THROW(ParseExpectations(bad, kModes, "s.yaml"), Error);
  const YAML::Node not_number = YAML::Load("{mutual.ate_rmse_m: {max: low}}");
  EXPECT_THROW(ParseExpectations(not_number, kModes, "s.yaml"), Error);
  const YAML::Node good = YAML::Load("{mutual.ate_rmse_m: {min: 0.001, max: 0.05}}");
  const std::vector<Expectation> parsed = ParseExpectations(good, kModes, "s.yaml");
  ASSERT_EQ(parsed.size(), 1u);
  EXPECT_EQ(parsed[0].Bounds(), "in [0.001, 0.05]");
}

TEST(ScenarioReportTest, SpreadIsNumpysMedianOverValuesThatExist) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Spread spread = SpreadOf({4, 1, nan, 3, 2});
  EXPECT_EQ(spread.runs, 5);
  EXPECT_EQ(spread.count, 4);
  EXPECT_DOUBLE_EQ(spread.median, 2.5);
  EXPECT_DOUBLE_EQ(spread.min, 1);
  EXPECT_DOUBLE_EQ(spread.max, 4);
  EXPECT_TRUE(std::isnan(SpreadOf({nan}).median));
}

TEST(ScenarioReportTest, ChecksUseMediansAndRatiosOfMedians) {
  SpreadTable table;
  table["pass1"]["mutual"]["ate_rmse_m"] = SpreadOf({0.02, 0.04, 0.03});
  table["pass1"]["plain"]["ate_rmse_m"] = SpreadOf({0.1});
  const std::vector<Expectation> expectations =
      ParseExpectations(YAML::Load("{mutual.ate_rmse_m: {max: 0.05}, mutual_vs_plain.ate_ratio: {max: 0.2},"
                                   " pass2.mutual.ate_rmse_m: {max: 1}}"),
                        kModes, "s.yaml");
  const std::vector<ExpectationResult> results = CheckExpectations(expectations, table);
  ASSERT_EQ(results.size(), 3u);
  EXPECT_TRUE(results[0].passed);
  EXPECT_DOUBLE_EQ(results[0].value, 0.03);
  EXPECT_FALSE(results[1].passed);  // 0.3 > 0.2
  EXPECT_DOUBLE_EQ(results[1].value, 0.3);
  EXPECT_FALSE(results[2].passed);  // no pass-2 value: NaN fails
}

// The share of the traffic's added error removed, from hand-made medians: plain 0.5 m with
// traffic and 0.1 m on the static twin, so the traffic adds 0.4 m; mutual at 0.14 m removes
// 90 % of it, mask-moveable at 0.3 m half, and a mode worse than plain a negative share.
TEST(ScenarioReportTest, TrafficErrorRemovedIsMeasuredAgainstThePlainOfTheStaticTwin) {
  SpreadTable table;
  table["pass2"]["plain"]["ate_rmse_m"] = SpreadOf({0.5});
  table["pass2"][kStaticTwinPlain]["ate_rmse_m"] = SpreadOf({0.1});
  table["pass2"]["mutual"]["ate_rmse_m"] = SpreadOf({0.12, 0.14, 0.2});
  table["pass2"]["mask-moveable"]["ate_rmse_m"] = SpreadOf({0.3});
  table["pass2"]["oracle"]["ate_rmse_m"] = SpreadOf({0.7});
  EXPECT_NEAR(TrafficErrorRemoved(table, "pass2", "mutual"), 0.9, 1e-12);
  EXPECT_NEAR(TrafficErrorRemoved(table, "pass2", "mask-moveable"), 0.5, 1e-12);
  EXPECT_NEAR(TrafficErrorRemoved(table, "pass2", "oracle"), -0.5, 1e-12);
  EXPECT_EQ(TrafficErrorRemoved(table, "pass2", "plain"), 0.0);
  // No twin, or a twin that drifts as much as plain among the traffic: nothing to measure.
  EXPECT_TRUE(std::isnan(TrafficErrorRemoved(table, "pass1", "mutual")));
  table["pass2"][kStaticTwinPlain]["ate_rmse_m"] = SpreadOf({0.5});
  EXPECT_TRUE(std::isnan(TrafficErrorRemoved(table, "pass2", "mutual")));

  table["pass2"][kStaticTwinPlain]["ate_rmse_m"] = SpreadOf({0.1});
  const std::vector<ExpectationResult> results = CheckExpectations(
      ParseExpectations(YAML::Load("{pass2.mutual.traffic_error_removed: {min: 0.8},"
                                   " pass2.mask-moveable.traffic_error_removed: {min: 0.8}}"),
                        kModes, "s.yaml"),
      table);
  ASSERT_EQ(results.size(), 2u);
  EXPECT_TRUE(results[0].passed);
  EXPECT_NEAR(results[0].value, 0.9, 1e-12);
  EXPECT_FALSE(results[1].passed);
  // Measured against plain: a scenario without plain cannot name it.
  EXPECT_NE(ParseError("mutual.traffic_error_removed", {"mutual"}).find("against plain, which does not run"),
            std::string::npos);
}

// Two of three repeats without an ATE (a pass that lost its map): the one value that is
// there must not pass the check for all three.
TEST(ScenarioReportTest, ACheckFailsWhenARepeatLacksTheValue) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  SpreadTable table;
  table["pass1"]["mutual"]["ate_rmse_m"] = SpreadOf({nan, nan, 0.01});
  table["pass1"]["plain"]["ate_rmse_m"] = SpreadOf({0.1});
  const std::vector<ExpectationResult> results = CheckExpectations(
      ParseExpectations(YAML::Load("{mutual.ate_rmse_m: {max: 0.05}, mutual_vs_plain.ate_ratio: {max: 0.5},"
                                   " plain.ate_rmse_m: {max: 1}}"),
                        kModes, "s.yaml"),
      table);
  ASSERT_EQ(results.size(), 3u);
  EXPECT_FALSE(results[0].passed);
  EXPECT_TRUE(std::isnan(results[0].value));
  EXPECT_FALSE(results[1].passed);
  EXPECT_TRUE(results[2].passed);
}

TEST(ScenarioReportTest, BenchSectionIsChecked) {
  const BenchSettings bench =
      BenchSettings::FromYaml(YAML::Load("{modes: [plain, mutual], repeats: 3, segmenter: gt, seed: 9}"), "s.yaml");
  EXPECT_EQ(bench.modes.size(), 2u);
  EXPECT_TRUE(bench.ModeIsDeterministic("mutual"));
  EXPECT_THROW(BenchSettings::FromYaml(YAML::Load("{repeat: 3}"), "s.yaml"), Error);
  EXPECT_THROW(BenchSettings::FromYaml(YAML::Load("{modes: [fast]}"), "s.yaml"), Error);
  EXPECT_THROW(BenchSettings::FromYaml(YAML::Load("{segmenter: magic}"), "s.yaml"), Error);
  EXPECT_TRUE(BenchSettings::FromYaml(YAML::Load("{static_twin: true}"), "s.yaml").static_twin);
  EXPECT_FALSE(bench.static_twin);
  try {
    BenchSettings::FromYaml(YAML::Load("{static_twin: maybe}"), "s.yaml");
    ADD_FAILURE() << "static_twin: maybe was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml: bench.static_twin: expected true or false, got 'maybe'"),
              std::string::npos)
        << e.what();
  }
}

// The oracle runs only where named, and on ground-truth masks whatever the segmenter.
TEST(ScenarioReportTest, OracleRunsOnlyWhenNamedAndOnce) {
  const BenchSettings defaults = BenchSettings::FromYaml(YAML::Load("{segmenter: fcis-like}"), "s.yaml");
  EXPECT_EQ(defaults.modes, (std::vector<std::string>{"plain", "mask-moveable", "mutual"}));
  const BenchSettings named =
      BenchSettings::FromYaml(YAML::Load("{modes: [plain, mutual, oracle], segmenter: fcis-like}"), "s.yaml");
  EXPECT_EQ(named.modes.back(), "oracle");
  EXPECT_TRUE(named.ModeIsDeterministic("oracle"));
  EXPECT_FALSE(named.ModeIsDeterministic("mutual"));
}

TEST(ScenarioReportTest, SegmenterStrengthScalesOnlyASimulatedSegmenter) {
  const BenchSettings preset = BenchSettings::FromYaml(YAML::Load("{segmenter: fcis-like}"), "s.yaml");
  EXPECT_EQ(preset.segmenter_strength, 1.0);
  EXPECT_EQ(preset.SegmenterLabel(), "fcis-like");
  const BenchSettings doubled =
      BenchSettings::FromYaml(YAML::Load("{segmenter: fcis-like, segmenter_strength: 2}"), "s.yaml");
  EXPECT_EQ(doubled.segmenter_strength, 2.0);
  EXPECT_EQ(doubled.SegmenterLabel(), "fcis-like@2");
  for (const char* bad : {"{segmenter_strength: -1}", "{segmenter_strength: 11}", "{segmenter_strength: much}",
                          "{segmenter: gt, segmenter_strength: 2}"}) {
    try {
      BenchSettings::FromYaml(YAML::Load(bad), "s.yaml");
      ADD_FAILURE() << bad << ": accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("s.yaml"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("segmenter_strength"), std::string::npos) << e.what();
    }
  }
}

// bench.refiner tunes the mutual loop's refinement (a sweep axis as bench.refiner.NAME).
TEST(ScenarioReportTest, RefinerOptionsNeedASimulatedSegmenterAndValidValues) {
  const BenchSettings bench = BenchSettings::FromYaml(
      YAML::Load("{segmenter: fcis-like, refiner: {trim_keeps_region_depth: 1, depth_tolerance: 0.1}}"), "s.yaml");
  EXPECT_EQ(bench.refiner, (std::vector<std::string>{"trim_keeps_region_depth=1", "depth_tolerance=0.1"}));
  const seg::RefinerOptions options = bench.LoopRefinerOptions();
  EXPECT_TRUE(options.trim_keeps_region_depth);
  EXPECT_DOUBLE_EQ(options.depth_tolerance, 0.1);
  EXPECT_EQ(BenchSettings().LoopRefinerOptions().trim_keeps_region_depth, seg::RefinerOptions().trim_keeps_region_depth);
  const struct {
    const char* yaml;
    const char* fragment;
  } bad[] = {
      {"{segmenter: gt, refiner: {depth_tolerance: 0.1}}", "ground-truth masks (gt) are not refined"},
      {"{refiner: {depth_tol: 0.1}}", "unknown field 'depth_tol'"},
      {"{refiner: {depth_tolerance: 2}}", "depth_tolerance: 2 is outside its range [0, 1)"},
      {"{refiner: {trim_keeps_region_depth: yes}}", "not a number: 'yes'"},
      {"{refiner: [depth_tolerance]}", "expected a mapping"},
  };
  for (const auto& c : bad) {
    try {
      BenchSettings::FromYaml(YAML::Load(c.yaml), "s.yaml");
      ADD_FAILURE() << c.yaml << ": accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("s.yaml"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.fragment), std::string::npos) << e.what();
    }
  }
}

// bench.tracker sets the tracker's options in every mode; nested mappings are the dotted
// names that --set bench.tracker.orb.max_features=1500 writes.
TEST(ScenarioReportTest, TrackerOptionsTakeNestedNamesAndAreChecked) {
  const BenchSettings bench = BenchSettings::FromYaml(
      YAML::Load("{segmenter: gt, tracker: {orb: {max_features: 1500}, min_tracking_inliers: 40}}"), "s.yaml");
  EXPECT_EQ(bench.tracker, (std::vector<std::string>{"orb.max_features=1500", "min_tracking_inliers=40"}));
  const slam::TrackerOptions options = bench.TrackerOverrides();
  EXPECT_EQ(options.orb.max_features, 1500);
  EXPECT_EQ(options.min_tracking_inliers, 40);
  EXPECT_EQ(options.local_bundle_adjustment, slam::TrackerOptions().local_bundle_adjustment);
  for (const char* bad : {"{tracker: {orb: {max_feature: 1500}}}", "{tracker: {local_bundle_adjustment: 2}}",
                          "{tracker: {min_tracking_inliers: [40]}}", "{tracker: 40}"}) {
    try {
      BenchSettings::FromYaml(YAML::Load(bad), "s.yaml");
      ADD_FAILURE() << bad << ": accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("s.yaml: bench"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("tracker"), std::string::npos) << e.what();
    }
  }
}

// bench.feature_jitter gives repeat r the feature budget shifted by 0, +1, -1, +2, ...
// jitters; every mode then runs each repeat, plain and the oracle too.
TEST(ScenarioReportTest, FeatureJitterShiftsEachRepeatsBudgetAndMakesEveryModeRepeat) {
  EXPECT_EQ(BenchSettings::FeatureBudgetShift(0), 0);
  EXPECT_EQ(BenchSettings::FeatureBudgetShift(1), 1);
  EXPECT_EQ(BenchSettings::FeatureBudgetShift(2), -1);
  EXPECT_EQ(BenchSettings::FeatureBudgetShift(3), 2);
  EXPECT_EQ(BenchSettings::FeatureBudgetShift(4), -2);

  const BenchSettings off = BenchSettings::FromYaml(YAML::Load("{modes: [plain, mutual, oracle]}"), "s.yaml");
  EXPECT_EQ(off.feature_jitter, 0);
  EXPECT_TRUE(off.ModeIsDeterministic("plain"));
  EXPECT_EQ(off.FeatureBudgetFor(3), slam::TrackerOptions().orb.max_features);
  EXPECT_EQ(off.TrackerAssignmentsFor(3), off.tracker);

  const BenchSettings jittered = BenchSettings::FromYaml(
      YAML::Load("{modes: [plain, mutual, oracle], repeats: 5, feature_jitter: 10, tracker: {orb: {max_features: 1500}}}"),
      "s.yaml");
  for (const char* mode : {"plain", "mutual", "oracle"}) EXPECT_FALSE(jittered.ModeIsDeterministic(mode)) << mode;
  std::vector<int> budgets;
  for (int repeat = 0; repeat < 5; ++repeat) budgets.push_back(jittered.FeatureBudgetFor(repeat));
  EXPECT_EQ(budgets, (std::vector<int>{1500, 1510, 1490, 1520, 1480}));
  // The jittered budget comes last, so it overrides the scenario's own.
  EXPECT_EQ(jittered.TrackerAssignmentsFor(4), (std::vector<std::string>{"orb.max_features=1500", "orb.max_features=1480"}));
  slam::TrackerOptions options;
  for (const std::string& assignment : jittered.TrackerAssignmentsFor(4)) slam::SetTrackerOption(&options, assignment);
  EXPECT_EQ(options.orb.max_features, 1480);

  const struct {
    const char* yaml;
    const char* fragment;
  } bad[] = {
      {"{feature_jitter: -5}", "feature_jitter: must be >= 0 (got -5)"},
      {"{feature_jitter: 600, repeats: 5}", "takes the feature budget of 1000 under 1"},
      {"{feature_jitter: some}", "bench.feature_jitter"},
      {"{feature_jitter: 2147483000, repeats: 2}", "past 2147483647"},
  };
  for (const auto& c : bad) {
    try {
      BenchSettings::FromYaml(YAML::Load(c.yaml), "s.yaml");
      ADD_FAILURE() << c.yaml << ": accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("s.yaml: bench"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.fragment), std::string::npos) << e.what();
    }
  }
  // Two repeats go up only; the third is the first to go down.
  EXPECT_NO_THROW(BenchSettings::FromYaml(YAML::Load("{feature_jitter: 1000, repeats: 2}"), "s.yaml"));
  EXPECT_NO_THROW(BenchSettings::FromYaml(YAML::Load("{feature_jitter: 999, repeats: 3}"), "s.yaml"));
  EXPECT_THROW(BenchSettings::FromYaml(YAML::Load("{feature_jitter: 1000, repeats: 3}"), "s.yaml"), Error);
}

}  // namespace
}  // namespace segslam::harness
