#include "harness/sweep.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_file.h"
#include "core/statistics.h"
#include "core/strings.h"
#include "core/yaml_file.h"
#include "harness/dataset_run.h"
#include "harness/report_document.h"
#include "harness/machine.h"
#include "harness/report_figures.h"
#include "harness/scenario_report.h"

namespace segslam::harness {

namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<std::string> SplitValues(const std::string& text) {
  if (!text.empty() && text.front() == '[') return {text};
  std::vector<std::string> values;
  std::string rest = text;
  for (std::size_t comma; (comma = rest.find(',')) != std::string::npos; rest = rest.substr(comma + 1)) {
    values.push_back(rest.substr(0, comma));
  }
  values.push_back(rest);
  return values;
}


// The median, min and max of one metric of one mode and pass in a point's results.json;
// NaN where the point has no value. `count` of its `runs` had a value.
struct PointValue {
  double median = kNaN, min = kNaN, max = kNaN;
  int count = 0, runs = 0;
};

double NumberOrNaN(const nlohmann::json& json, const char* key) {
  return json.contains(key) && json[key].is_number() ? json[key].get<double>() : kNaN;
}

PointValue ValueOf(const nlohmann::json& results, const std::string& pass, const std::string& mode,
                   const std::string& metric) {
  if (!results.contains("summary")) return {};
  const nlohmann::json& summary = results["summary"];
  if (!summary.contains(pass) || !summary[pass].contains(mode) || !summary[pass][mode].contains(metric)) return {};
  const nlohmann::json& s = summary[pass][mode][metric];
  return {NumberOrNaN(s, "median"), NumberOrNaN(s, "min"), NumberOrNaN(s, "max"), s.value("count", 0),
          s.value("runs", 0)};
}

std::string Cell(double value, const char* format) {
  return std::isnan(value) ? std::string("n/a") : fmt::format(fmt::runtime(format), value);
}

// Runs without a value are named, as in the scenario report: "0.0123 (2 of 3 runs)".
std::string Spread(const PointValue& v, const char* format) {
  if (std::isnan(v.median)) return "n/a";
  std::string text = Cell(v.median, format);
  if (v.min != v.max) text += " [" + Cell(v.min, format) + ", " + Cell(v.max, format) + "]";
  if (v.count < v.runs) text += fmt::format(" ({} of {} runs)", v.count, v.runs);
  return text;
}

struct PlotSpec {
  std::string file;     // under figures/
  std::string pass;
  std::string metric;
  std::string title;
  std::string y_label;
  std::vector<std::string> modes;  // empty = every mode that ran
};

}  // namespace

AxisPlacement PlaceAxisOnPlot(const SweepAxis& axis) {
  AxisPlacement placement;
  std::vector<double> numbers;
  for (const std::string& value : axis.values) {
    try {
      std::size_t used = 0;
      numbers.push_back(std::stod(value, &used));
      if (used != value.size()) placement.numeric = false;
    } catch (const std::exception&) {
      placement.numeric = false;
    }
  }
  placement.value_index.resize(axis.values.size());
  std::iota(placement.value_index.begin(), placement.value_index.end(), std::size_t{0});
  if (placement.numeric) {
    std::sort(placement.value_index.begin(), placement.value_index.end(),
              [&](std::size_t a, std::size_t b) { return numbers[a] < numbers[b]; });
    for (std::size_t v : placement.value_index) placement.x.push_back(numbers[v]);
    if (std::adjacent_find(placement.x.begin(), placement.x.end()) == placement.x.end()) return placement;
  }
  placement.numeric = false;
  placement.x.clear();
  std::iota(placement.value_index.begin(), placement.value_index.end(), std::size_t{0});
  for (std::size_t i = 0; i < axis.values.size(); ++i) placement.x.push_back(static_cast<double>(i));
  return placement;
}

SweepGrid SweepGrid::FromSetOptions(const std::vector<std::string>& set_options) {
  SweepGrid grid;
  for (const std::string& option : set_options) {
    const std::size_t equals = option.find('=');
    if (equals == std::string::npos || equals == 0 || equals + 1 == option.size()) {
      throw Error("sweep --set " + option + ": expected KEY=VALUE or KEY=V1,V2,..., e.g. city.moving_cars=0,4,8");
    }
    const std::string key = option.substr(0, equals);
    const std::vector<std::string> values = SplitValues(option.substr(equals + 1));
    for (const std::string& value : values) {
      if (value.empty()) throw Error("sweep --set " + option + ": an empty value");
    }
    if (values.size() == 1) {
      grid.fixed_overrides.push_back(option);
    } else {
      grid.axes.push_back({key, values});
    }
  }
  return grid;
}

int SweepGrid::PointCount() const {
  int count = 1;
  for (const SweepAxis& axis : axes) count *= static_cast<int>(axis.values.size());
  return count;
}

std::vector<std::string> SweepGrid::PointAssignments(int index) const {
  std::vector<std::string> assignments(axes.size());
  for (int a = static_cast<int>(axes.size()) - 1; a >= 0; --a) {
    const int n = static_cast<int>(axes[a].values.size());
    assignments[a] = axes[a].key + "=" + axes[a].values[index % n];
    index /= n;
  }
  return assignments;
}

std::string SweepGrid::PointName(int index) const {
  std::string name = Join(PointAssignments(index), "__");
  for (char& c : name) {
    const bool plain = std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '=' || c == '-';
    if (!plain) c = '_';
  }
  return name.empty() ? "single" : name;
}

SweepGrid SweepGrid::WithSetOptions(const std::vector<std::string>& set_options) const {
  SweepGrid grid = *this;
  const SweepGrid given = FromSetOptions(set_options);
  auto axis_of = [&grid](const std::string& key) {
    return std::find_if(grid.axes.begin(), grid.axes.end(), [&key](const SweepAxis& a) { return a.key == key; });
  };
  for (const std::string& option : given.fixed_overrides) {
    const auto axis = axis_of(option.substr(0, option.find('=')));
    if (axis != grid.axes.end()) grid.axes.erase(axis);
    grid.fixed_overrides.push_back(option);
  }
  for (const SweepAxis& axis : given.axes) {
    const auto existing = axis_of(axis.key);
    if (existing != grid.axes.end()) {
      existing->values = axis.values;
    } else {
      grid.axes.push_back(axis);
    }
  }
  return grid;
}

namespace {

// One value of a sweep file as --set would spell it: a scalar's text, or a list in
// YAML's flow style ("[0, 0.5, 0]").
std::string ValueText(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

}  // namespace

bool SweepFile::Recognize(const fs::path& file) {
  try {
    const YAML::Node root = YAML::LoadFile(file.string());
    return root.IsMap() && root["axes"];
  } catch (const std::exception&) {
    return false;  // not YAML at all, or not a file: the scenario reader says what is wrong
  }
}

SweepFile SweepFile::Load(const fs::path& file) {
  const std::string origin = file.string();
  const YAML::Node root = LoadYamlFile(file);
  if (!root.IsMap()) throw Error(origin + ": a sweep file is a map with scenario: and axes:");
  for (const auto& entry : root) {
    const std::string key = entry.first.Scalar();
    if (key != "name" && key != "scenario" && key != "set" && key != "axes") {
      throw Error(origin + ": unknown key '" + PrintableText(key) + "' (known: name, scenario, set, axes)");
    }
  }
  SweepFile sweep;
  sweep.name = root["name"] && root["name"].IsScalar() ? root["name"].Scalar() : file.stem().string();
  if (!root["scenario"] || !root["scenario"].IsScalar()) {
    throw Error(origin + ": scenario: the scenario file to sweep is needed");
  }
  sweep.scenario = (file.parent_path() / root["scenario"].Scalar()).lexically_normal();
  if (!fs::exists(sweep.scenario)) throw Error(origin + ": scenario " + sweep.scenario.string() + ": no such file");
  std::vector<std::string> set_options;
  if (const YAML::Node set = root["set"]) {
    if (!set.IsSequence()) throw Error(origin + ": set: expected a list of KEY=VALUE");
    for (const YAML::Node& item : set) {
      const std::string option = item.IsScalar() ? item.Scalar() : "";
      const std::size_t equals = option.find('=');
      if (equals == std::string::npos || equals == 0 || equals + 1 == option.size()) {
        throw Error(origin + ": set: '" + option + "': expected KEY=VALUE");
      }
      sweep.grid.fixed_overrides.push_back(option);
    }
  }
  const YAML::Node axes = root["axes"];
  if (!axes.IsMap() || axes.size() == 0) {
    throw Error(origin + ": axes: expected a map of KEY: [V1, V2, ...], e.g. office.people_walking: [0, 2, 4]");
  }
  for (const auto& entry : axes) {
    SweepAxis axis;
    axis.key = entry.first.Scalar();
    if (!entry.second.IsSequence() || entry.second.size() < 2) {
      throw Error(origin + ": axes: " + axis.key + ": expected a list of at least two values (one value goes in set:)");
    }
    for (const YAML::Node& value : entry.second) {
      if (!value.IsScalar() && !value.IsSequence()) {
        throw Error(origin + ": axes: " + axis.key + ": a value must be a number, a word or a list");
      }
      axis.values.push_back(ValueText(value));
    }
    sweep.grid.axes.push_back(axis);
  }
  return sweep;
}

nlohmann::json SweepGrid::ToJson() const {
  nlohmann::json json = {{"axes", nlohmann::json::array()}, {"fixed_overrides", fixed_overrides}};
  for (const SweepAxis& axis : axes) json["axes"].push_back({{"key", axis.key}, {"values", axis.values}});
  return json;
}

SweepGrid SweepGrid::FromJson(const nlohmann::json& json, const std::string& origin) {
  SweepGrid grid;
  try {
    for (const auto& axis : json.at("axes")) {
      grid.axes.push_back({axis.at("key").get<std::string>(), axis.at("values").get<std::vector<std::string>>()});
    }
    grid.fixed_overrides = json.at("fixed_overrides").get<std::vector<std::string>>();
  } catch (const nlohmann::json::exception& e) {
    throw Error(origin + ": not a sweep grid (" + e.what() + ")");
  }
  return grid;
}

Shard Shard::FromSlurmArray(const std::function<const char*(const char*)>& variable) {
  const auto number = [&](const char* name, std::optional<long long> fallback) -> long long {
    const char* text = variable(name);
    if (text == nullptr || *text == '\0') {
      if (fallback) return *fallback;
      throw Error(std::string("sweep --shard slurm: ") + name +
                  " is not set; submit the sweep as a Slurm job array (sbatch --array=1-N, or the script "
                  "`segslam sweep ... --emit-sbatch DIR` writes)");
    }
    try {
      std::size_t used = 0;
      const long long value = std::stoll(text, &used);
      if (used != std::strlen(text)) throw std::invalid_argument(text);
      return value;
    } catch (const std::exception&) {
      throw Error(std::string("sweep --shard slurm: ") + name + "=" + text + " is not a whole number");
    }
  };
  const long long id = number("SLURM_ARRAY_TASK_ID", std::nullopt);
  const long long count = number("SLURM_ARRAY_TASK_COUNT", std::nullopt);
  const long long first = number("SLURM_ARRAY_TASK_MIN", 0LL);
  const long long step = number("SLURM_ARRAY_TASK_STEP", 1LL);
  const long long offset = id - first;
  if (count < 1 || count > std::numeric_limits<int>::max() || step < 1 || offset < 0 || offset % step != 0 ||
      offset / step >= count) {
    throw Error(fmt::format("sweep --shard slurm: task {} is not one of {} tasks from {} in steps of {}; give the "
                            "array as a range (--array=1-N or FIRST-LAST:STEP), not a list",
                            id, count, first, step));
  }
  Shard shard;
  shard.index = static_cast<int>(offset / step) + 1;
  shard.count = static_cast<int>(count);
  return shard;
}

Shard Shard::Parse(const std::string& text) {
  if (text == "slurm") return FromSlurmArray([](const char* name) { return std::getenv(name); });
  Shard shard;
  const std::size_t slash = text.find('/');
  try {
    if (slash == std::string::npos) throw std::invalid_argument(text);
    std::size_t used_index = 0, used_count = 0;
    shard.index = std::stoi(text.substr(0, slash), &used_index);
    shard.count = std::stoi(text.substr(slash + 1), &used_count);
    if (used_index != slash || used_count != text.size() - slash - 1) throw std::invalid_argument(text);
  } catch (const std::exception&) {
    throw Error("sweep --shard " + text + ": expected I/N, e.g. 2/4");
  }
  if (shard.count < 1 || shard.index < 1 || shard.index > shard.count) {
    throw Error("sweep --shard " + text + ": needs 1 <= I <= N");
  }
  return shard;
}

namespace {

// Every point's results.json (and its report and figures), from the first input that has
// it, copied into out_dir's points/ unless it is already there. Throws naming the points no input has.
std::vector<nlohmann::json> GatherPointResults(const SweepGrid& grid, const std::vector<fs::path>& inputs,
                                               const fs::path& out_dir) {
  const int points = grid.PointCount();
  std::vector<nlohmann::json> results(points);
  std::vector<std::string> missing;
  for (int p = 0; p < points; ++p) {
    const std::string name = grid.PointName(p);
    bool found = false;
    for (const fs::path& input : inputs) {
      const fs::path file = input / "points" / name / "results.json";
      if (!fs::exists(file)) continue;
      results[p] = ReadJsonFile(file);
      const fs::path target = out_dir / "points" / name / "results.json";
      if (!fs::exists(target) || !fs::equivalent(file, target)) {
        fs::create_directories(target.parent_path());
        // The point's report comes along, so the merged report's pointer to it holds
        // (not its runs/, which can be large).
        for (const char* part : {"report.md", "report.html", "figures"}) {
          if (fs::exists(file.parent_path() / part)) {
            fs::copy(file.parent_path() / part, target.parent_path() / part,
                     fs::copy_options::recursive | fs::copy_options::overwrite_existing);
          }
        }
        WriteFileAtomically(target, results[p].dump(2) + "\n");
      }
      found = true;
      break;
    }
    if (!found) missing.push_back(name);
  }
  if (!missing.empty()) {
    throw Error(fmt::format("sweep merge: {} of {} points have no results.json in {}: {}", missing.size(), points,
                            inputs.size() == 1 ? inputs.front().string() : "any of the folders given",
                            Join(missing, ", ")));
  }
  return results;
}

// What the points ran: the modes, in the paper's order, and whether there was a pass 2.
struct SweepContents {
  std::vector<std::string> modes;
  bool two_pass = false;
  bool has_plain = false;
  bool has_mutual = false;
};

SweepContents ContentsOf(const std::vector<nlohmann::json>& results) {
  SweepContents contents;
  contents.modes = ModesThatRan(results);
  contents.two_pass = std::any_of(results.begin(), results.end(), [](const nlohmann::json& r) {
    return r.contains("summary") && r["summary"].contains("pass2");
  });
  const auto ran = [&](const char* mode) {
    return std::find(contents.modes.begin(), contents.modes.end(), mode) != contents.modes.end();
  };
  contents.has_plain = ran("plain");
  contents.has_mutual = ran("mutual");
  return contents;
}

// A row per point, a column group per mode.
ReportTable SweepTable(const SweepGrid& grid, const std::vector<nlohmann::json>& results,
                       const SweepContents& contents) {
  const bool two_pass = contents.two_pass;
  // Against plain: mutual, and the oracle (what a perfect judgement would give) if it ran.
  std::vector<std::string> ratio_modes;
  for (const char* mode : {"mutual", "oracle"}) {
    const bool ran = std::find(contents.modes.begin(), contents.modes.end(), mode) != contents.modes.end();
    if (contents.has_plain && ran) ratio_modes.push_back(mode);
  }
  ReportTable table;
  table.caption = "Median over repeats [min, max]; pass 2 scored in the pass-1 map frame (ATE) and against pass 1's "
                  "estimate at the same place (map-relative, docs/metrics.md)";
  for (const SweepAxis& axis : grid.axes) table.header.push_back(axis.key);
  for (const std::string& mode : contents.modes) {
    table.header.push_back(mode + " ATE p1 [m]");
    // ATE covers the localized frames only: where a mode breaks, this says how much.
    table.header.push_back(mode + " localized p1");
    if (two_pass) {
      table.header.push_back(mode + " ATE p2 [m]");
      table.header.push_back(mode + " localized p2");
      // How well pass 2 relocalizes and tracks on the map, pass 1's own error left out.
      table.header.push_back(mode + " map-relative p2 [m]");
      table.header.push_back(mode + " within 0.1 m, 1 deg p2");
    }
  }
  for (const std::string& mode : ratio_modes) {
    table.header.push_back(mode + "/plain ATE p1");
    if (two_pass) table.header.push_back(mode + "/plain ATE p2");
  }
  if (contents.has_mutual) {
    // What the density axes mean to SLAM: how much of what it saw moved (run_evaluation.h).
    table.header.push_back("moving features p1, mean");
    table.header.push_back("mutual mIoU raw -> refined");
  }
  for (int p = 0; p < grid.PointCount(); ++p) {
    const nlohmann::json& r = results[p];
    std::vector<std::string> row;
    for (const std::string& assignment : grid.PointAssignments(p)) row.push_back(assignment.substr(assignment.find('=') + 1));
    for (const std::string& mode : contents.modes) {
      row.push_back(Spread(ValueOf(r, "pass1", mode, "ate_rmse_m"), "{:.4f}"));
      row.push_back(Cell(100 * ValueOf(r, "pass1", mode, "localized_share").median, "{:.1f}%"));
      if (two_pass) {
        row.push_back(Spread(ValueOf(r, "pass2", mode, "ate_rmse_m"), "{:.4f}"));
        row.push_back(Cell(100 * ValueOf(r, "pass2", mode, "localized_share").median, "{:.1f}%"));
        row.push_back(Spread(ValueOf(r, "pass2", mode, "reloc_trans_rmse_m"), "{:.4f}"));
        row.push_back(Cell(100 * ValueOf(r, "pass2", mode, "reloc_within_share").median, "{:.1f}%"));
      }
    }
    for (const std::string& mode : ratio_modes) {
      for (const std::string pass : {"pass1", "pass2"}) {
        if (pass == std::string("pass2") && !two_pass) continue;
        row.push_back(Cell(ValueOf(r, pass, mode, "ate_rmse_m").median / ValueOf(r, pass, "plain", "ate_rmse_m").median,
                           "{:.2f}"));
      }
    }
    if (contents.has_mutual) {
      row.push_back(Cell(100 * ValueOf(r, "pass1", "mutual", "moving_feature_share_mean").median, "{:.1f}%"));
      row.push_back(Cell(100 * ValueOf(r, "pass1", "mutual", "seg_raw_miou").median, "{:.1f}") + " -> " +
                    Cell(100 * ValueOf(r, "pass1", "mutual", "seg_refined_miou").median, "{:.1f}"));
    }
    table.rows.push_back(row);
  }
  return table;
}

// The share of the traffic's added error each mode removes (points run with the static
// twin, harness/scenario_expectations.h), per pass: the median over the points and the
// worst point. Empty when no point ran the twin.
ReportTable TrafficErrorRemovedTable(const SweepGrid& grid, const std::vector<nlohmann::json>& results,
                                     const SweepContents& contents) {
  ReportTable table;
  table.caption = "The share of the traffic's added error each mode removes, (plain - mode) / (plain - plain on "
                  "the static twin), over the points that ran the static twin: median and worst point";
  table.header = {"mode", "points"};
  for (const std::string pass : {"pass1", "pass2"}) {
    table.header.push_back(pass + " median [%]");
    table.header.push_back(pass + " worst [%]");
    table.header.push_back(pass + " worst point");
  }
  for (const std::string& mode : contents.modes) {
    if (mode == "plain") continue;
    std::vector<std::string> row = {mode, ""};
    int points = 0;
    for (const std::string pass : {"pass1", "pass2"}) {
      std::vector<double> removed;
      int worst = -1;
      double worst_value = kNaN;
      for (int p = 0; p < grid.PointCount(); ++p) {
        const nlohmann::json& r = results[static_cast<size_t>(p)];
        if (!r.contains("static_twin")) continue;
        const nlohmann::json& of_pass = r["static_twin"].value(kTrafficErrorRemoved, nlohmann::json::object());
        const double value = of_pass.contains(pass) ? NumberOrNaN(of_pass[pass], mode.c_str()) : kNaN;
        if (std::isnan(value)) continue;
        removed.push_back(value);
        if (worst < 0 || value < worst_value) {
          worst = p;
          worst_value = value;
        }
      }
      points = std::max(points, static_cast<int>(removed.size()));
      row.push_back(removed.empty() ? "n/a" : Cell(100 * Median(removed), "{:.0f}"));
      row.push_back(Cell(100 * worst_value, "{:.0f}"));
      row.push_back(worst < 0 ? "n/a" : Join(grid.PointAssignments(worst), ", "));
    }
    row[1] = std::to_string(points);
    if (points > 0) table.rows.push_back(row);
  }
  return table;
}

// sweep_results.json: the grid, and per point its assignments, folder, code version and
// summary.
nlohmann::json MergedResults(const SweepGrid& grid, const std::vector<nlohmann::json>& results) {
  nlohmann::json merged = {{"grid", grid.ToJson()}, {"points", nlohmann::json::array()}};
  for (int p = 0; p < grid.PointCount(); ++p) {
    const nlohmann::json& r = results[p];
    merged["points"].push_back({{"assignments", grid.PointAssignments(p)},
                                {"folder", "points/" + grid.PointName(p)},
                                {"code_version", r.value("code_version", "")},
                                {"summary", r.value("summary", nlohmann::json::object())}});
  }
  return merged;
}

// The report's title and what it states of the sweep: files, grid, code versions,
// machine, segmenters and seeds.
ReportDocument SweepDocument(const nlohmann::json& sweep, const SweepGrid& grid,
                             const std::vector<nlohmann::json>& results) {
  const std::string scenario_name = results.front().value("scenario", std::string("?"));
  ReportDocument document("segslam sweep: " + (sweep.contains("name") ? sweep["name"].get<std::string>() + " (" +
                                                                            scenario_name + ")"
                                                                      : scenario_name));
  if (sweep.contains("sweep_file")) document.AddMetadata("sweep file", sweep["sweep_file"].get<std::string>());
  document.AddMetadata("scenario file", results.front().value("scenario_file", std::string("?")));
  document.AddMetadata("grid", [&] {
    std::vector<std::string> parts;
    for (const SweepAxis& axis : grid.axes) parts.push_back(axis.key + " = " + Join(axis.values, ", "));
    return parts.empty() ? std::string("one point") : Join(parts, "; ");
  }());
  if (!grid.fixed_overrides.empty()) document.AddMetadata("fixed overrides", Join(grid.fixed_overrides, " "));
  std::set<std::string> versions;
  for (const nlohmann::json& r : results) versions.insert(r.value("code_version", std::string("?")));
  document.AddMetadata("code version", Join({versions.begin(), versions.end()}, ", "));
  const nlohmann::json machine = results.front().value("machine", nlohmann::json());
  if (machine.is_object()) document.AddMetadata("machine", MachineLine(machine));
  // The segmenter can be an axis itself (bench.segmenter, bench.segmenter_strength).
  std::vector<std::string> segmenters;
  for (const nlohmann::json& r : results) {
    const nlohmann::json point_bench = r.value("bench", nlohmann::json::object());
    const std::string label = SimulatedSegmenterLabel(point_bench.value("segmenter", std::string("?")),
                                                      point_bench.value("segmenter_strength", 1.0));
    if (std::find(segmenters.begin(), segmenters.end(), label) == segmenters.end()) segmenters.push_back(label);
  }
  const nlohmann::json bench = results.front().value("bench", nlohmann::json::object());
  document.AddMetadata("bench", fmt::format("{} repeat(s) per mode, segmenter {}, seeds from {}",
                                            bench.value("repeats", 0),
                                            segmenters.size() == 1 ? segmenters.front()
                                                                   : Join(segmenters, ", ") + " (per point)",
                                            bench.value("seed", 0)));
  return document;
}

// The plots against the first axis (other axes' values become more series), written to
// out_dir/figures/ and added to the document.
void AddSweepPlots(const SweepGrid& grid, const std::vector<nlohmann::json>& results,
                   const SweepContents& contents, const fs::path& out_dir, ReportDocument* document) {
  std::vector<PlotSpec> plots = {{"sweep_ate_pass1.png", "pass1", "ate_rmse_m", "ATE, pass 1", "ATE RMSE [m]", {}}};
  if (contents.two_pass) {
    plots.push_back({"sweep_ate_pass2.png", "pass2", "ate_rmse_m", "ATE, pass 2 on the pass-1 map", "ATE RMSE [m]", {}});
    plots.push_back({"sweep_localized_pass2.png", "pass2", "localized_share", "Relocalization: pass-2 frames localized",
                     "share of frames", {}});
    plots.push_back({"sweep_map_relative_pass2.png", "pass2", "reloc_trans_rmse_m",
                     "Pass 2 against pass 1's estimate at the same place", "map-relative error RMSE [m]", {}});
    plots.push_back({"sweep_map_relative_within_pass2.png", "pass2", "reloc_within_share",
                     "Pass-2 frames within 0.1 m and 1 deg of pass 1's estimate", "share of frames", {}});
  }
  if (contents.has_mutual) {
    plots.push_back({"sweep_moving_features_pass1.png", "pass1", "moving_feature_share_mean",
                     "Moving features (mutual), pass 1", "mean share of features on movers", {"mutual"}});
    plots.push_back({"sweep_miou_pass1.png", "pass1", "seg_refined_miou", "Segmentation in the loop (mutual), pass 1",
                     "mIoU", {"mutual"}});
  }
  const SweepAxis& axis = grid.axes.front();
  document->AddHeading("Against " + axis.key, 2);
  const AxisPlacement placement = PlaceAxisOnPlot(axis);
  const int per_value = grid.PointCount() / static_cast<int>(axis.values.size());
  fs::create_directories(out_dir / "figures");
  for (const PlotSpec& spec : plots) {
    std::vector<PlotSeries> series;
    const std::vector<std::string>& plot_modes = spec.modes.empty() ? contents.modes : spec.modes;
    for (const std::string& mode : plot_modes) {
      for (int rest = 0; rest < per_value; ++rest) {
        PlotSeries s;
        s.name = mode;
        if (per_value > 1) {
          const std::vector<std::string> assignments = grid.PointAssignments(rest);
          s.name += " (" + Join({assignments.begin() + 1, assignments.end()}, ", ") + ")";
        }
        for (const std::size_t v : placement.value_index) {
          const PointValue value = ValueOf(results[static_cast<int>(v) * per_value + rest], spec.pass, mode, spec.metric);
          s.y.push_back(value.median);
          s.y_min.push_back(value.min);
          s.y_max.push_back(value.max);
        }
        series.push_back(s);
      }
    }
    LinePlotOptions options;
    options.title = spec.title;
    options.x_label = axis.key + (placement.numeric ? "" : " (" + Join(axis.values, ", ") + ")");
    options.y_label = spec.y_label;
    WriteFigure(out_dir / "figures" / spec.file, DrawLinePlot(options, placement.x, series).image);
    document->AddImage("figures/" + spec.file,
                       spec.title + " against " + axis.key + " (median over repeats, bars from min to max)");
  }
}

}  // namespace

std::string MergeSweep(const std::vector<fs::path>& inputs, const fs::path& out_dir) {
  if (inputs.empty()) throw Error("sweep merge: no sweep folders given");
  const fs::path grid_file = inputs.front() / "sweep.json";
  const nlohmann::json sweep = ReadJsonFile(grid_file);
  const SweepGrid grid = SweepGrid::FromJson(sweep.value("grid", nlohmann::json::object()), grid_file.string());
  for (std::size_t i = 1; i < inputs.size(); ++i) {
    const fs::path other = inputs[i] / "sweep.json";
    const nlohmann::json other_sweep = ReadJsonFile(other);
    if (other_sweep.value("grid", nlohmann::json::object()) != sweep["grid"]) {
      throw Error("sweep merge: " + other.string() + " holds another grid than " + grid_file.string());
    }
    if (other_sweep.value("settings", nlohmann::json()) != sweep.value("settings", nlohmann::json())) {
      throw Error("sweep merge: " + other.string() + " was run with other settings than " + grid_file.string() +
                  " (scenario, --frames, --modes, --repeats, --segmenter or --set)");
    }
  }
  const std::vector<nlohmann::json> results = GatherPointResults(grid, inputs, out_dir);
  const SweepContents contents = ContentsOf(results);
  const ReportTable table = SweepTable(grid, results, contents);

  ReportDocument document = SweepDocument(sweep, grid, results);
  document.AddHeading("Results per point", 2);
  document.AddTable(table);
  if (const ReportTable removed = TrafficErrorRemovedTable(grid, results, contents); !removed.rows.empty()) {
    document.AddHeading("The traffic's added error removed (static twin)", 2);
    document.AddTable(removed);
  }
  document.AddParagraph("Each point's own report (tables, trajectories) is in points/<point>/report.html.");
  if (!grid.axes.empty()) AddSweepPlots(grid, results, contents, out_dir, &document);
  WriteFileAtomically(out_dir / "sweep_results.json", MergedResults(grid, results).dump(2) + "\n");
  document.Write(out_dir);

  std::ostringstream text;
  text << Join(table.header, " | ") << "\n";
  for (const auto& row : table.rows) text << Join(row, " | ") << "\n";
  return text.str();
}

}  // namespace segslam::harness
