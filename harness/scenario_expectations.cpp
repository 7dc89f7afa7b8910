// Metric names, `expect:` thresholds, the spreads of repeated runs and the checks of
// the thresholds on them (harness/scenario_expectations.h).
#include "harness/scenario_expectations.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "core/error.h"
#include "core/statistics.h"
#include "core/strings.h"

namespace segslam::harness {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

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
    if (!Contains(kScenarioPasses, parts[0])) throw unknown("'" + parts[0] + "' is not pass1 or pass2");
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
  if (metric == kTrafficErrorRemoved && !name.IsRatio()) {
    if (!Contains(modes, std::string("plain"))) throw unknown(metric + " is measured against plain, which does not run");
    name.metric = metric;
    return name;
  }
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

const Spread* FindSpread(const SpreadTable& table, const std::string& pass, const std::string& mode,
                         const std::string& metric) {
  const auto p = table.find(pass);
  if (p == table.end()) return nullptr;
  const auto m = p->second.find(mode);
  if (m == p->second.end()) return nullptr;
  const auto v = m->second.find(metric);
  return v == m->second.end() ? nullptr : &v->second;
}

namespace {

// The median of `metric` over `mode`'s runs; NaN when a run lacks the value (no ATE after
// a pass that lost its map, say): the median of the others would hide it.
double CompleteMedian(const SpreadTable& table, const std::string& pass, const std::string& mode,
                      const std::string& metric) {
  const Spread* s = FindSpread(table, pass, mode, metric);
  return s == nullptr || s->count < s->runs ? kNaN : s->median;
}

}  // namespace

double TrafficErrorRemoved(const SpreadTable& table, const std::string& pass, const std::string& mode) {
  const double plain = CompleteMedian(table, pass, "plain", "ate_rmse_m");
  const double twin = CompleteMedian(table, pass, kStaticTwinPlain, "ate_rmse_m");
  const double with_mode = CompleteMedian(table, pass, mode, "ate_rmse_m");
  const double added = plain - twin;
  return added > 0 ? (plain - with_mode) / added : kNaN;
}

std::vector<ExpectationResult> CheckExpectations(const std::vector<Expectation>& expectations, const SpreadTable& table) {
  std::vector<ExpectationResult> results;
  for (const Expectation& expectation : expectations) {
    const MetricName& name = expectation.name;
    auto median = [&](const std::string& mode) { return CompleteMedian(table, name.pass, mode, name.metric); };
    ExpectationResult result;
    result.expectation = expectation;
    if (name.metric == kTrafficErrorRemoved) {
      result.value = TrafficErrorRemoved(table, name.pass, name.mode);
    } else {
      result.value = name.IsRatio() ? median(name.mode) / median(name.denominator_mode) : median(name.mode);
    }
    result.passed = std::isfinite(result.value) && (!expectation.min || result.value >= *expectation.min) &&
                    (!expectation.max || result.value <= *expectation.max);
    results.push_back(result);
  }
  return results;
}

}  // namespace segslam::harness
