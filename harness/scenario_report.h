// The report of a scenario run: what ran (scenario, dataset, bench settings, every run),
// the spreads over repeats and the checked expectations, written as results.json,
// report.md and report.html (the paper's tables, and the figures that were drawn), as
// text for the terminal and as JUnit XML. The settings are in harness/bench_settings.h,
// metric names, spreads and thresholds in harness/scenario_expectations.h, the figures in
// harness/scenario_figures.h.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/bench_settings.h"
#include "harness/report_document.h"
#include "harness/scenario_expectations.h"

namespace segslam::harness {

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
  // BenchSettings::static_twin: plain's run on the static twin, and its dataset. Its
  // metrics are in `spreads` as mode kStaticTwinPlain.
  std::vector<RepeatRun> static_twin_runs;
  std::string static_twin_dataset_dir;
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

// The modes, in the paper's order (mutual::SlamModeNames), that ran in any of these
// results.json documents (ScenarioReport::ToJson); one without a bench section ran none.
std::vector<std::string> ModesThatRan(const std::vector<nlohmann::json>& results);

}  // namespace segslam::harness
