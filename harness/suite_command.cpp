// `segslam scenario suite SUITE.yaml`: several scenario runs gathered into the paper's
// tables (scenarios/suites/paper_tables.yaml: Table I, ATE on six TUM-like office sequences;
// Tables II and IV, raw vs refined segmentation; Table III, relocalization on two-pass
// city routes). Each entry is one `scenario run` (harness/scenario_runner.h) into
// OUT/<entry>/; OUT/report.html, report.md and suite_results.json hold the joined tables.
//
// Suite file:
//   name: paper_tables
//   entries:
//     - name: fr3_walking_xyz              # a row label, unique, [A-Za-z0-9._-]
//       scenario: ../office_walking_xyz.yaml  # relative to the suite file's folder
//       set: [office.frames=300]           # optional --set overrides
//       tables: [ate, segmentation]        # which joined tables show this entry:
//                                          # ate, segmentation, relocalization
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/statistics.h"
#include "core/yaml_file.h"
#include "harness/cli_numbers.h"
#include "harness/commands.h"
#include "harness/dataset_run.h"
#include "harness/machine.h"
#include "harness/report_document.h"
#include "harness/scenario_runner.h"
#include "scenes/scenario.h"

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

const std::set<std::string> kTables = {"ate", "segmentation", "relocalization"};

struct SuiteEntry {
  std::string name;
  fs::path scenario;
  std::vector<std::string> overrides;
  std::set<std::string> tables;
};

struct Suite {
  std::string name;
  std::vector<SuiteEntry> entries;
};

Suite LoadSuite(const fs::path& file) {
  const std::string origin = file.string();
  const YAML::Node root = LoadYamlFile(file);
  if (!root.IsMap()) throw Error(origin + ": a suite file is a map with name: and entries:");
  for (const auto& key : root) {
    const std::string k = key.first.as<std::string>();
    if (k != "name" && k != "entries") throw Error(origin + ": unknown key '" + PrintableText(k) + "' (known: name, entries)");
  }
  Suite suite;
  suite.name = root["name"] ? root["name"].as<std::string>() : file.stem().string();
  if (!root["entries"] || !root["entries"].IsSequence() || root["entries"].size() == 0) {
    throw Error(origin + ": entries: a non-empty list is needed");
  }
  std::set<std::string> names;
  for (std::size_t i = 0; i < root["entries"].size(); ++i) {
    const YAML::Node node = root["entries"][i];
    const std::string where = fmt::format("{}: entries[{}]", origin, i);
    if (!node.IsMap()) throw Error(where + ": expected a map");
    for (const auto& key : node) {
      const std::string k = key.first.as<std::string>();
      if (k != "name" && k != "scenario" && k != "set" && k != "tables") {
        throw Error(where + ": unknown key '" + PrintableText(k) + "' (known: name, scenario, set, tables)");
      }
    }
    SuiteEntry entry;
    if (!node["name"] || !node["scenario"]) throw Error(where + ": name: and scenario: are required");
    entry.name = node["name"].as<std::string>();
    const bool plain_name = !entry.name.empty() && std::all_of(entry.name.begin(), entry.name.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
    });
    // It names the entry's report folder: "." or ".." would be the suite's own or its parent.
    if (!plain_name || entry.name == "." || entry.name == "..") {
      throw Error(where + ": name '" + PrintableText(entry.name) + "' must be letters, digits, '.', '_' or '-', and not . or ..");
    }
    if (!names.insert(entry.name).second) throw Error(where + ": name '" + entry.name + "' is used twice");
    entry.scenario = file.parent_path() / node["scenario"].as<std::string>();
    if (!fs::exists(entry.scenario)) throw Error(where + ": scenario " + entry.scenario.string() + ": no such file");
    if (node["set"]) {
      if (!node["set"].IsSequence()) throw Error(where + ": set: expected a list of KEY=VALUE");
      for (const auto& item : node["set"]) entry.overrides.push_back(item.as<std::string>());
    }
    if (!node["tables"] || !node["tables"].IsSequence()) {
      throw Error(where + ": tables: expected a list of ate, segmentation, relocalization");
    }
    for (const auto& item : node["tables"]) {
      const std::string table = item.as<std::string>();
      if (!kTables.count(table)) {
        throw Error(where + ": tables: unknown table '" + PrintableText(table) + "' (known: ate, segmentation, relocalization)");
      }
      entry.tables.insert(table);
    }
    suite.entries.push_back(entry);
  }
  return suite;
}

struct SuiteArgs {
  ScenarioRunRequest run;  // repeats, modes, frames, cache... shared by every entry
  std::string suite_file;
  std::string out_dir;
  bool check_only = false;  // --check: validate every entry, run none
};

double Median(const nlohmann::json& results, const std::string& pass, const std::string& mode,
              const std::string& metric, const char* which = "median") {
  const nlohmann::json summary = results.value("summary", nlohmann::json::object());
  if (!summary.contains(pass) || !summary[pass].contains(mode) || !summary[pass][mode].contains(metric)) return NAN;
  const nlohmann::json& value = summary[pass][mode][metric][which];
  return value.is_number() ? value.get<double>() : NAN;
}

std::string Cell(double value, const char* format, double scale = 1) {
  return std::isnan(value) ? std::string("n/a") : fmt::format(fmt::runtime(format), scale * value);
}

std::string WithSpread(const nlohmann::json& results, const std::string& pass, const std::string& mode,
                       const std::string& metric, const char* format, double scale = 1) {
  const double median = Median(results, pass, mode, metric);
  const double low = Median(results, pass, mode, metric, "min"), high = Median(results, pass, mode, metric, "max");
  std::string text = Cell(median, format, scale);
  if (std::isnan(median)) return text;
  if (low != high) text += " [" + Cell(low, format, scale) + ", " + Cell(high, format, scale) + "]";
  // Runs without a value are named, as in the scenario report.
  const double count = Median(results, pass, mode, metric, "count"), runs = Median(results, pass, mode, metric, "runs");
  if (count < runs) text += fmt::format(" ({:.0f} of {:.0f} runs)", count, runs);
  return text;
}

// Median, min and max of per-route values, as the paper's Table III gives each system's
// ATE over its 40 routes; NaN (a mode that localized nothing on a route) is left out.
struct OverRoutes {
  int routes = 0;  // with a value
  double median = NAN, min = NAN, max = NAN;

  explicit OverRoutes(std::vector<double> values) {
    values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return std::isnan(v); }), values.end());
    routes = static_cast<int>(values.size());
    if (values.empty()) return;
    const auto [low, high] = std::minmax_element(values.begin(), values.end());
    min = *low;
    max = *high;
    median = segslam::Median(std::move(values));
  }
  std::string Text(const char* format, double scale = 1) const {
    if (routes == 0) return "n/a";
    return Cell(median, format, scale) + " [" + Cell(min, format, scale) + ", " + Cell(max, format, scale) + "]";
  }
  nlohmann::json ToJson() const {
    if (routes == 0) return nullptr;
    return {{"median", median}, {"min", min}, {"max", max}, {"routes", routes}};
  }
};

// The paper's tables over the suite's entries, each entry in the tables it asked for:
// Table I (ATE), Tables II and IV (segmentation in the loop), Table III (relocalization,
// a row per route and, as the paper gives it, one over all routes).
struct SuiteTables {
  ReportTable ate;
  ReportTable segmentation;
  ReportTable relocalization;
  // Table III over all routes: {mode: {"ate_rmse_m": S, "localized_share": S,
  // "reloc_trans_rmse_m": S, "reloc_within_share": S}}, each S
  // {"median", "min", "max", "routes"} over the routes' medians (null where no route has
  // a value); null with fewer than two routes.
  nlohmann::json relocalization_over_routes;
};

SuiteTables MakeSuiteTables(const Suite& suite, const std::vector<nlohmann::json>& results) {
  const std::vector<std::string> modes = ModesThatRan(results);
  const bool ratio = std::count(modes.begin(), modes.end(), "plain") && std::count(modes.begin(), modes.end(), "mutual");
  SuiteTables tables{
      {"ATE RMSE [m], pass 1, aligned to the ground truth; a mode localized on fewer than all frames says its share "
       "(ATE covers those only)",
       {"sequence"},
       {}},
      {"Raw vs refined masks of the mutual loop (SLAM poses) [%]",
       {"sequence", "raw mAP", "raw AP50", "raw mIoU", "refined mAP", "refined AP50", "refined mIoU"}, {}},
      {"Pass 2 on pass 1's long-term map, not re-aligned: localized share and ATE RMSE [m] (the paper's figure, "
       "which includes pass 1's map error); map-relative: RMSE [m] of each pass-2 pose against pass 1's estimate at "
       "the nearest pass-1 place (pass 1's error drops out) and the share of frames within 0.1 m and 1 deg of it",
       {"route"}, {}},
      nlohmann::json()};
  ReportTable& ate = tables.ate;
  ReportTable& seg = tables.segmentation;
  ReportTable& reloc = tables.relocalization;
  for (const std::string& mode : modes) ate.header.push_back(mode);
  if (ratio) ate.header.push_back("mutual / plain");
  for (const std::string& mode : modes) {
    reloc.header.push_back(mode + " localized");
    reloc.header.push_back(mode + " ATE");
    reloc.header.push_back(mode + " map-relative");
  }
  if (ratio) reloc.header.push_back("mutual / plain");
  // Per mode, each route's median over repeats: localized share and ATE.
  std::map<std::string, std::vector<double>> route_localized, route_ate, route_reloc, route_within;
  for (std::size_t i = 0; i < suite.entries.size(); ++i) {
    const SuiteEntry& entry = suite.entries[i];
    const nlohmann::json& r = results[i];
    if (entry.tables.count("ate")) {
      std::vector<std::string> row = {entry.name};
      for (const std::string& mode : modes) {
        std::string cell = WithSpread(r, "pass1", mode, "ate_rmse_m", "{:.4f}");
        const double localized = Median(r, "pass1", mode, "localized_share");
        if (localized < 1) cell += " (" + Cell(localized, "{:.1f}% localized", 100) + ")";
        row.push_back(cell);
      }
      if (ratio) {
        row.push_back(Cell(Median(r, "pass1", "mutual", "ate_rmse_m") / Median(r, "pass1", "plain", "ate_rmse_m"), "{:.2f}"));
      }
      ate.rows.push_back(row);
    }
    if (entry.tables.count("segmentation")) {
      for (const std::string pass : {"pass1", "pass2"}) {
        std::vector<std::string> row = {entry.name + " " + pass};
        for (const std::string kind : {"raw", "refined"}) {
          for (const std::string metric : {"map", "ap50", "miou"}) {
            row.push_back(WithSpread(r, pass, "mutual", "seg_" + kind + "_" + metric, "{:.1f}", 100));
          }
        }
        seg.rows.push_back(row);
      }
    }
    if (entry.tables.count("relocalization")) {
      std::vector<std::string> row = {entry.name};
      for (const std::string& mode : modes) {
        row.push_back(Cell(Median(r, "pass2", mode, "localized_share"), "{:.1f}%", 100));
        row.push_back(WithSpread(r, "pass2", mode, "ate_rmse_m", "{:.4f}"));
        row.push_back(WithSpread(r, "pass2", mode, "reloc_trans_rmse_m", "{:.4f}") + " (" +
                      Cell(Median(r, "pass2", mode, "reloc_within_share"), "{:.1f}% within", 100) + ")");
        route_localized[mode].push_back(Median(r, "pass2", mode, "localized_share"));
        route_ate[mode].push_back(Median(r, "pass2", mode, "ate_rmse_m"));
        route_reloc[mode].push_back(Median(r, "pass2", mode, "reloc_trans_rmse_m"));
        route_within[mode].push_back(Median(r, "pass2", mode, "reloc_within_share"));
      }
      if (ratio) {
        row.push_back(Cell(Median(r, "pass2", "mutual", "ate_rmse_m") / Median(r, "pass2", "plain", "ate_rmse_m"), "{:.2f}"));
      }
      reloc.rows.push_back(row);
    }
  }
  if (reloc.rows.size() >= 2) {
    std::vector<std::string> row = {fmt::format("all {} routes: median [min, max]", reloc.rows.size())};
    for (const std::string& mode : modes) {
      const OverRoutes localized(route_localized[mode]), ate_over_routes(route_ate[mode]);
      const OverRoutes reloc_over_routes(route_reloc[mode]), within(route_within[mode]);
      row.push_back(localized.Text("{:.1f}%", 100));
      row.push_back(ate_over_routes.Text("{:.4f}"));
      row.push_back(reloc_over_routes.Text("{:.4f}") + " (" + within.Text("{:.1f}%", 100) + " within)");
      tables.relocalization_over_routes[mode] = {{"ate_rmse_m", ate_over_routes.ToJson()},
                                                 {"localized_share", localized.ToJson()},
                                                 {"reloc_trans_rmse_m", reloc_over_routes.ToJson()},
                                                 {"reloc_within_share", within.ToJson()}};
    }
    // The ratio of the two medians over routes, as the paper compares its Table III.
    if (ratio) {
      row.push_back(Cell(OverRoutes(route_ate["mutual"]).median / OverRoutes(route_ate["plain"]).median, "{:.2f}"));
    }
    reloc.rows.push_back(row);
  }
  return tables;
}

// Every entry's scenario, overrides, bench settings and expectations, checked before the
// first run: a bad one in the last entry would otherwise stop the suite hours in.
void CheckSuiteEntries(const Suite& suite, const SuiteArgs& args) {
  for (const SuiteEntry& entry : suite.entries) {
    scenes::Scenario scenario = scenes::LoadScenario(entry.scenario);
    try {
      scenes::ApplyOverrides(scenario, entry.overrides);
    } catch (const Error& e) {
      throw Error(args.suite_file + ": entry " + entry.name + ": set: " + e.what());
    }
    try {
      ScenarioRunRequest request = args.run;
      request.scenario_file = entry.scenario.string();
      request.overrides = entry.overrides;
      EffectiveBench(scenario, request);
      ParseExpectations(scenario.expect, BenchSettings::FromYaml(scenario.bench, request.scenario_file).modes,
                        request.scenario_file);
    } catch (const Error& e) {
      throw Error(args.suite_file + ": entry " + entry.name + ": " + e.what());
    }
  }
}

// Runs entry i as `scenario run` would, into out_dir/<entry name>/, and prints its checks.
ScenarioReport RunSuiteEntry(const Suite& suite, std::size_t i, const SuiteArgs& args, const fs::path& out_dir) {
  const SuiteEntry& entry = suite.entries[i];
  ScenarioRunRequest request = args.run;
  request.scenario_file = entry.scenario.string();
  request.overrides = entry.overrides;
  request.out_dir = (out_dir / entry.name).string();
  request.junit_file.clear();
  request.progress_prefix = fmt::format("[{} {}/{}] ", entry.name, i + 1, suite.entries.size());
  fmt::print("[{}/{}] {}: {}{}\n", i + 1, suite.entries.size(), entry.name, entry.scenario.string(),
             entry.overrides.empty() ? "" : " --set " + fmt::format("{}", fmt::join(entry.overrides, " --set ")));
  std::fflush(stdout);
  ScenarioReport report = RunScenarioToReport(request);
  for (const ExpectationResult& check : report.checks) {
    fmt::print("  {}  {} {}\n", check.passed ? "PASS" : "FAIL", check.expectation.name.text,
               std::isnan(check.value) ? std::string("n/a") : fmt::format("{:.4g} {}", check.value, check.expectation.Bounds()));
  }
  return report;
}

int RunSuite(const SuiteArgs& args) {
  const auto start = std::chrono::steady_clock::now();
  const Suite suite = LoadSuite(args.suite_file);
  CheckSuiteEntries(suite, args);
  if (args.check_only) {
    fmt::print("suite {}: {} entries checked (scenarios, overrides, bench settings, thresholds); nothing run\n",
               suite.name, suite.entries.size());
    return 0;
  }
  const fs::path out_dir = args.out_dir.empty() ? fs::path("reports") / suite.name : fs::path(args.out_dir);
  fmt::print("segslam scenario suite: {} ({} entries) into {}\n", suite.name, suite.entries.size(), out_dir.string());
  std::vector<nlohmann::json> results;
  int failed_checks = 0, checks = 0, not_checked = 0, entries_failed = 0;
  for (std::size_t i = 0; i < suite.entries.size(); ++i) {
    const ScenarioReport report = RunSuiteEntry(suite, i, args, out_dir);
    checks += static_cast<int>(report.checks.size());
    not_checked += static_cast<int>(report.not_checked.size());
    entries_failed += report.Passed() ? 0 : 1;
    failed_checks += static_cast<int>(std::count_if(report.checks.begin(), report.checks.end(),
                                                    [](const ExpectationResult& check) { return !check.passed; }));
    results.push_back(report.ToJson());
  }

  ReportDocument document("segslam suite: " + suite.name);
  document.AddMetadata("suite file", args.suite_file);
  document.AddMetadata("code version", results.front().value("code_version", std::string("?")));
  document.AddMetadata("machine", MachineLine(results.front().value("machine", nlohmann::json())));
  const nlohmann::json bench = results.front()["bench"];
  const std::string segmenter =
      SimulatedSegmenterLabel(bench.value("segmenter", std::string("?")), bench.value("segmenter_strength", 1.0));
  document.AddMetadata("bench", fmt::format("{} repeat(s) per mode, segmenter {}, seeds from {}; median [min, max]",
                                            bench.value("repeats", 0), segmenter, bench.value("seed", 0)));
  std::string text;
  auto add_table = [&](const std::string& title, const ReportTable& table) {
    if (table.rows.empty()) return;
    document.AddHeading(title, 2);
    document.AddTable(table);
    text += "\n" + title + "\n" + fmt::format("{}", fmt::join(table.header, " | ")) + "\n";
    for (const auto& row : table.rows) text += fmt::format("{}", fmt::join(row, " | ")) + "\n";
  };
  const SuiteTables tables = MakeSuiteTables(suite, results);
  add_table("Table I: ATE on TUM-like office sequences", tables.ate);
  add_table("Tables II and IV: segmentation in the loop", tables.segmentation);
  add_table("Table III: relocalization on two-pass city routes", tables.relocalization);
  document.AddHeading("Entries", 2);
  for (const SuiteEntry& entry : suite.entries) {
    document.AddParagraph(entry.name + ": " + entry.name + "/report.html (every table, figures, each run)");
  }

  nlohmann::json joined = {{"suite", suite.name}, {"entries", nlohmann::json::array()}};
  for (std::size_t i = 0; i < suite.entries.size(); ++i) {
    const SuiteEntry& entry = suite.entries[i];
    joined["entries"].push_back({{"name", entry.name},
                                 {"scenario", entry.scenario.string()},
                                 {"overrides", entry.overrides},
                                 {"report", entry.name + "/report.html"},
                                 {"summary", results[i]["summary"]},
                                 {"expectations", results[i]["expectations"]}});
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  joined["relocalization_over_routes"] = tables.relocalization_over_routes;
  joined["seconds"] = seconds;
  joined["checks"] = checks;
  joined["failed_checks"] = failed_checks;
  joined["not_checked"] = not_checked;
  joined["passed"] = entries_failed == 0;
  WriteFileAtomically(out_dir / "suite_results.json", joined.dump(2) + "\n");
  document.Write(out_dir);
  fmt::print("{}", text);
  fmt::print("suite {}: {} entries, {} of {} expectations passed{}, {:.1f} s, report in {}\n", suite.name,
             suite.entries.size(), checks - failed_checks, checks,
             not_checked > 0 ? fmt::format(", {} not checked", not_checked) : std::string(), seconds,
             (out_dir / "report.html").string());
  // An entry that could check none of its expectations verified nothing (ScenarioReport::Passed).
  return entries_failed == 0 ? 0 : 2;
}

}  // namespace

void AddSuiteCommand(CLI::App& scenario, std::function<int()>* action) {
  auto args = std::make_shared<SuiteArgs>();
  CLI::App* suite = scenario.add_subcommand(
      "suite",
      "Run every entry of a suite file (e.g. scenarios/suites/paper_tables.yaml) as a scenario run and join them into the "
      "paper's tables. Exit code 0: every threshold passes; 2: one fails; 1: an error");
  suite->add_option("suite", args->suite_file, "Suite YAML file")->required();
  suite->add_option("--out,-o", args->out_dir, "Report directory (default reports/<suite name>)");
  suite->add_option("--repeats", args->run.repeats, "Runs per mode (default: each scenario's bench.repeats)")
      ->check(WholeNumberIn(1, kMaxRepeats));
  suite->add_option("--modes", args->run.modes, "Comma-separated modes (default: each scenario's bench.modes)");
  suite->add_option("--segmenter", args->run.segmenter, "Simulated segmenter preset, or gt");
  suite->add_option("--jobs,-j", args->run.jobs,
                  "Runs at a time, each on its own thread (a run uses about one core; the results do not "
                  "depend on it)")
      ->check(WholeNumberIn(1, kMaxThreads))
      ->capture_default_str();
  suite->add_option("--frames", args->run.frames, "Only the first N frames per pass (0 = all)")
      ->check(WholeNumberIn(0, kMaxFrames, "0 = all"));
  suite->add_option("--cache", args->run.cache_dir, "Folder of cached datasets")->capture_default_str();
  suite->add_option("--gl", args->run.gl, "Off-screen GL back-end for generation: osmesa or egl")->capture_default_str();
  suite->add_flag("-q,--quiet", args->run.quiet, "No progress bars");
  suite->add_flag("--check", args->check_only,
                  "Check the suite file and every entry (scenario, overrides, bench settings, thresholds), run nothing");
  suite->callback([args, action] { *action = [args] { return RunSuite(*args); }; });
}

}  // namespace segslam::harness
