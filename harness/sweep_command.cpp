// `segslam sweep SCENARIO --set key=v1,v2,...` or `segslam sweep SWEEP_FILE`: a scenario
// run per grid point (harness/sweep.h), then the merged table and plots; `segslam sweep
// merge` joins the folders of a sweep split with --shard.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/input_file.h"
#include "core/json_file.h"
#include "harness/cli_numbers.h"
#include "harness/commands.h"
#include "harness/scenario_runner.h"
#include "harness/sweep.h"
#include "scenes/scenario.h"
#include "segslam_version.h"  // generated at build time: SEGSLAM_VERSION

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

struct SweepArgs {
  std::string file;        // a scenario file, or a sweep file (harness/sweep.h: SweepFile)
  ScenarioRunRequest run;  // modes, repeats, ... shared by every point
  std::vector<std::string> set_options;
  std::string out_dir;
  std::string shard = "1/1";
  std::string emit_sbatch_dir;             // write Slurm scripts there instead of running
  std::vector<std::string> sbatch_options;  // e.g. --partition=cpu, one #SBATCH line each
  int array_tasks = 0;                      // 0 = one task per point
};

struct SweepMergeArgs {
  std::vector<std::string> inputs;
  std::string out_dir;
};

// True when the point's folder already holds the results of this grid point from this
// code version (an interrupted or re-submitted sweep does not redo it).
bool PointIsDone(const fs::path& point_dir, const std::vector<std::string>& overrides) {
  const fs::path file = point_dir / "results.json";
  if (!fs::exists(file)) return false;
  try {
    const nlohmann::json results = ReadJsonFile(file);
    return results.value("overrides", std::vector<std::string>{}) == overrides &&
           results.value("code_version", std::string()) == SEGSLAM_VERSION;
  } catch (const std::exception&) {
    return false;  // unreadable: run the point again
  }
}

// The overrides of grid point p: the grid's fixed ones, then the point's own.
std::vector<std::string> PointOverrides(const SweepGrid& grid, int p) {
  std::vector<std::string> overrides = grid.fixed_overrides;
  for (const std::string& assignment : grid.PointAssignments(p)) overrides.push_back(assignment);
  return overrides;
}

// Applies every point's overrides (bench settings included) to the scenario, so that a
// bad point fails before the first run. Errors name the sweep file's point when there
// is one.
void CheckEveryPoint(const scenes::Scenario& base, const SweepGrid& grid, const ScenarioRunRequest& run,
                     const std::string& sweep_file) {
  for (int p = 0; p < grid.PointCount(); ++p) {
    scenes::Scenario scenario = base;
    try {
      scenes::ApplyOverrides(scenario, PointOverrides(grid, p));
      const BenchSettings bench = EffectiveBench(scenario, run);
      for (const SweepAxis& axis : grid.axes) {
        if (axis.key == "bench.segmenter_strength" && bench.segmenter == "gt") {
          throw Error("sweep: bench.segmenter_strength scales a simulated segmenter's errors; the segmenter is gt");
        }
        if (axis.key.rfind("bench.refiner.", 0) == 0 && bench.segmenter == "gt") {
          throw Error("sweep: " + axis.key + " tunes the refinement of a simulated segmenter's masks; the segmenter is gt");
        }
      }
    } catch (const Error& e) {
      if (sweep_file.empty()) throw;
      throw Error(sweep_file + ": point " + grid.PointName(p) + ": " + e.what());
    }
  }
}

// Writes out_dir/sweep.json, which names the sweep's scenario, grid and settings. A folder
// that holds another sweep (another grid or settings, or an unreadable sweep.json) is
// refused, so shards and reruns of one sweep share a folder and different sweeps never mix.
void ClaimSweepFolder(const fs::path& out_dir, const nlohmann::json& sweep) {
  fs::create_directories(out_dir);
  const fs::path sweep_file = out_dir / "sweep.json";
  if (fs::exists(sweep_file)) {
    nlohmann::json existing;
    try {
      existing = ReadJsonFile(sweep_file);
    } catch (const Error&) {
      // unreadable: refused below like another sweep's
    }
    const nlohmann::json existing_settings = existing.value("settings", nlohmann::json());
    if (existing_settings.is_object() && !existing_settings.contains("scenario")) {
      throw Error("sweep: " + out_dir.string() +
                  " holds a sweep of an older segslam, which did not record the scenario's content; choose another "
                  "--out");
    }
    if (existing.value("grid", nlohmann::json()) != sweep["grid"] || existing_settings != sweep["settings"]) {
      throw Error("sweep: " + out_dir.string() +
                  " holds another sweep (sweep.json differs: grid, scenario file or its content, --frames, --modes, "
                  "--repeats, --segmenter or --set); choose another --out");
    }
  }
  WriteFileAtomically(sweep_file, sweep.dump(2) + "\n");
}

// Runs grid point p as a scenario run into out_dir/points/<point name>, unless an
// earlier sweep left its results there; `ordinal` of `mine` counts this shard's points.
void RunPoint(const ScenarioRunRequest& run, const SweepGrid& grid, int p, const fs::path& out_dir, int ordinal,
              int mine) {
  ScenarioRunRequest request = run;
  request.overrides = PointOverrides(grid, p);
  request.out_dir = (out_dir / "points" / grid.PointName(p)).string();
  request.progress_prefix = fmt::format("[point {}/{}] ", ordinal, mine);
  request.junit_file.clear();
  if (PointIsDone(request.out_dir, request.overrides)) {
    fmt::print("[point {}/{}] {}: done before, kept\n", ordinal, mine, grid.PointName(p));
    return;
  }
  fmt::print("[point {}/{}] {}\n", ordinal, mine, grid.PointName(p));
  std::fflush(stdout);
  const ScenarioReport report = RunScenarioToReport(request);
  int passed = 0;
  for (const ExpectationResult& check : report.checks) passed += check.passed ? 1 : 0;
  fmt::print("[point {}/{}] {}: {} runs in {:.1f} s, {} of {} expectations passed\n", ordinal, mine,
             grid.PointName(p), report.runs.size(), report.seconds, passed, report.checks.size());
  std::fflush(stdout);
}

// The argument as one word for bash: as it is when it has no special characters, else
// single-quoted.
std::string ShellWord(const std::string& text) {
  const bool plain = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || std::strchr("_./=,:+-@%", c) != nullptr;
  });
  if (plain) return text;
  std::string quoted = "'";
  for (const char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string ShellLine(const std::vector<std::string>& words) {
  std::string line;
  for (const std::string& word : words) line += (line.empty() ? "" : " ") + ShellWord(word);
  return line;
}

// Writes DIR/sweep_array.sbatch (the sweep as a job array, each task a shard: --shard
// slurm), DIR/sweep_merge.sbatch (the merge, after every task succeeded) and DIR/submit.sh,
// which submits both. Paths are made absolute: the jobs start elsewhere, on other nodes.
void EmitSbatch(const SweepArgs& args, const fs::path& out_dir, int points, const std::string& name) {
  const fs::path dir = fs::absolute(args.emit_sbatch_dir);
  fs::create_directories(dir / "logs");
  const fs::path binary = fs::read_symlink("/proc/self/exe");
  const int tasks = args.array_tasks > 0 ? std::min(args.array_tasks, points) : points;

  std::vector<std::string> sweep = {binary.string(), "sweep", fs::absolute(args.file).string()};
  for (const std::string& set : args.set_options) sweep.insert(sweep.end(), {"--set", set});
  sweep.insert(sweep.end(), {"--out", fs::absolute(out_dir).string(), "--cache", fs::absolute(args.run.cache_dir).string(),
                             "--jobs", std::to_string(args.run.jobs), "--gl", args.run.gl});
  if (args.run.repeats > 0) sweep.insert(sweep.end(), {"--repeats", std::to_string(args.run.repeats)});
  if (!args.run.modes.empty()) sweep.insert(sweep.end(), {"--modes", args.run.modes});
  if (!args.run.segmenter.empty()) sweep.insert(sweep.end(), {"--segmenter", args.run.segmenter});
  if (args.run.frames > 0) sweep.insert(sweep.end(), {"--frames", std::to_string(args.run.frames)});
  const std::vector<std::string> merge = {binary.string(), "sweep", "merge", fs::absolute(out_dir).string()};

  const auto header = [&](const std::string& job, const std::string& log) {
    std::string text = "#!/bin/bash\n";
    text += "#SBATCH --job-name=" + ShellWord("segslam-" + name + "-" + job) + "\n";
    text += "#SBATCH --output=" + ShellWord((dir / "logs" / log).string()) + "\n";
    for (const std::string& option : args.sbatch_options) text += "#SBATCH " + option + "\n";
    return text;
  };
  std::string array = header("array", "array_%A_%a.out");
  array += fmt::format("#SBATCH --array=1-{}\n#SBATCH --cpus-per-task={}\n", tasks, args.run.jobs);
  array += fmt::format(
      "# Written by `segslam sweep --emit-sbatch`: task k of this array runs shard k/{} of the sweep's {} points\n"
      "# (point p belongs to shard p % {} + 1); datasets two tasks need are generated once in the shared\n"
      "# --cache, the others waiting for it. Submit with submit.sh, which queues the merge after it.\n"
      "set -euo pipefail\ncd {}\nexec {} --shard slurm -q\n",
      tasks, points, tasks, ShellWord(fs::current_path().string()), ShellLine(sweep));
  std::string merge_job = header("merge", "merge_%j.out");
  merge_job += fmt::format(
      "# Written by `segslam sweep --emit-sbatch`: joins the array's points into one report.\n"
      "set -euo pipefail\ncd {}\nexec {}\n",
      ShellWord(fs::current_path().string()), ShellLine(merge));
  const std::string submit =
      "#!/bin/bash\n"
      "# Submits the sweep's job array, and its merge to run when every task has succeeded.\n"
      "set -euo pipefail\n"
      "here=$(cd \"$(dirname \"$0\")\" && pwd)\n"
      "array=$(sbatch --parsable \"$here/sweep_array.sbatch\")\n"
      "array=${array%%;*}  # --parsable prints JOBID;CLUSTER on a federation\n"
      "merge=$(sbatch --parsable --dependency=afterok:\"$array\" --kill-on-invalid-dep=yes \"$here/sweep_merge.sbatch\")\n"
      "merge=${merge%%;*}\n"
      "echo \"array job $array, merge job $merge\"\n";
  WriteFileAtomically(dir / "sweep_array.sbatch", array);
  WriteFileAtomically(dir / "sweep_merge.sbatch", merge_job);
  WriteFileAtomically(dir / "submit.sh", submit);
  fs::permissions(dir / "submit.sh", fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                  fs::perm_options::add);
  fmt::print("sweep: {} points as a Slurm array of {} task(s) and a merge job: {}\nsubmit with: bash {}\n"
             "the merged report will be in {}\n",
             points, tasks, dir.string(), (dir / "submit.sh").string(), (fs::absolute(out_dir) / "report.html").string());
}

int RunSweep(const SweepArgs& args) {
  const auto start = std::chrono::steady_clock::now();
  // A sweep file brings its scenario and grid; --set lays over them.
  std::optional<SweepFile> sweep_file_spec;
  if (SweepFile::Recognize(args.file)) sweep_file_spec = SweepFile::Load(args.file);
  ScenarioRunRequest run = args.run;
  run.scenario_file = sweep_file_spec ? sweep_file_spec->scenario.string() : args.file;
  const SweepGrid grid = sweep_file_spec ? sweep_file_spec->grid.WithSetOptions(args.set_options)
                                         : SweepGrid::FromSetOptions(args.set_options);
  if (!args.emit_sbatch_dir.empty() && args.shard != "1/1") {
    throw Error("sweep: --emit-sbatch writes a job array whose tasks take their shards from Slurm; leave --shard out");
  }
  const Shard shard = args.emit_sbatch_dir.empty() ? Shard::Parse(args.shard) : Shard{};
  const scenes::Scenario base = scenes::LoadScenario(run.scenario_file);
  CheckEveryPoint(base, grid, run, sweep_file_spec ? args.file : std::string());

  const std::string default_name = sweep_file_spec ? sweep_file_spec->name : base.name + "-sweep";
  const fs::path out_dir = args.out_dir.empty() ? fs::path("reports") / default_name : fs::path(args.out_dir);
  // What every point's results depend on besides the grid: a folder (or a shard to merge)
  // made with other settings holds another sweep.
  // The scenario's content, not only its path: a file edited between two runs into one
  // folder is another sweep.
  YAML::Emitter scenario_yaml;
  scenario_yaml << scenes::ScenarioToYaml(base);
  const nlohmann::json settings = {{"scenario_file", run.scenario_file}, {"scenario", scenario_yaml.c_str()},
                                   {"frames", run.frames},
                                   {"modes", run.modes},                 {"repeats", run.repeats},
                                   {"segmenter", run.segmenter},         {"overrides", run.overrides}};
  nlohmann::json sweep = {{"scenario_file", run.scenario_file}, {"grid", grid.ToJson()}, {"settings", settings}};
  if (sweep_file_spec) {
    sweep["sweep_file"] = args.file;
    sweep["name"] = sweep_file_spec->name;
  }
  if (!args.emit_sbatch_dir.empty() && fs::exists(args.emit_sbatch_dir) && !fs::is_directory(args.emit_sbatch_dir)) {
    throw FileError(args.emit_sbatch_dir, "is not a folder; --emit-sbatch takes the folder to write the Slurm scripts into");
  }
  ClaimSweepFolder(out_dir, sweep);

  const int points = grid.PointCount();
  if (!args.emit_sbatch_dir.empty()) {
    EmitSbatch(args, out_dir, points, default_name);
    return 0;
  }
  int mine = 0;
  for (int p = 0; p < points; ++p) mine += shard.Owns(p) ? 1 : 0;
  fmt::print("segslam sweep: {} points ({}), shard {}/{} runs {} of them, into {}\n", points,
             grid.axes.empty() ? std::string("no axis") : fmt::format("{} axes", grid.axes.size()), shard.index,
             shard.count, mine, out_dir.string());
  int ordinal = 0;
  for (int p = 0; p < points; ++p) {
    if (shard.Owns(p)) RunPoint(run, grid, p, out_dir, ++ordinal, mine);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (shard.count > 1) {
    fmt::print("sweep shard {}/{}: {} points in {:.1f} s; when every shard is done: segslam sweep merge {} ...\n",
               shard.index, shard.count, mine, seconds, out_dir.string());
    return 0;
  }
  fmt::print("\n{}", MergeSweep({out_dir}, out_dir));
  fmt::print("sweep: {} points in {:.1f} s, report in {}\n", points, seconds, (out_dir / "report.html").string());
  return 0;
}

int RunSweepMerge(const SweepMergeArgs& args) {
  std::vector<fs::path> inputs(args.inputs.begin(), args.inputs.end());
  const fs::path out_dir = args.out_dir.empty() ? inputs.front() : fs::path(args.out_dir);
  if (out_dir != inputs.front()) {
    fs::create_directories(out_dir);
    WriteFileAtomically(out_dir / "sweep.json", ReadFileText(inputs.front() / "sweep.json"));
  }
  fmt::print("{}", MergeSweep(inputs, out_dir));
  fmt::print("sweep merge: report in {}\n", (out_dir / "report.html").string());
  return 0;
}

}  // namespace

void AddSweepCommand(CLI::App& app, std::function<int()>* action) {
  auto args = std::make_shared<SweepArgs>();
  auto merge_args = std::make_shared<SweepMergeArgs>();
  CLI::App* sweep = app.add_subcommand(
      "sweep",
      "A scenario run per point of a parameter grid (a sweep file's axes, or --set key=v1,v2,...), then a "
      "table and plots of ATE, relocalization, moving features and mIoU against the parameter, per mode");
  sweep->add_option("file", args->file,
                    "A scenario YAML file (the grid from --set), or a sweep file with its scenario and axes "
                    "(scenarios/sweeps/)");
  sweep->add_option("--set", args->set_options,
                    "KEY=V1,V2,... sweeps KEY over the values; KEY=VALUE fixes it (repeatable; several lists make a "
                    "grid)");
  sweep->add_option("--out,-o", args->out_dir, "Sweep folder (default reports/<scenario name>-sweep)");
  sweep->add_option("--shard", args->shard,
                    "Run only shard I of N (I/N): point p belongs to shard p % N + 1; 'slurm': this Slurm array "
                    "task's shard (SLURM_ARRAY_TASK_ID of SLURM_ARRAY_TASK_COUNT)")
      ->capture_default_str();
  sweep->add_option("--emit-sbatch", args->emit_sbatch_dir,
                    "Write Slurm scripts into this folder instead of running: the sweep as a job array (one task per "
                    "point, or --array-tasks), a merge job after it, and submit.sh to queue both");
  sweep->add_option("--sbatch", args->sbatch_options,
                    "An sbatch option for the emitted jobs, e.g. --sbatch=--partition=cpu (repeatable)");
  sweep->add_option("--array-tasks", args->array_tasks, "Tasks of the emitted array (default: one per point)")
      ->check(WholeNumberIn(1, 100000));
  sweep->add_option("--repeats", args->run.repeats, "Runs per mode and point (default: the scenario's bench.repeats)")
      ->check(WholeNumberIn(1, kMaxRepeats));
  sweep->add_option("--modes", args->run.modes, "Comma-separated modes (default: the scenario's bench.modes)");
  sweep->add_option("--segmenter", args->run.segmenter, "Simulated segmenter preset, or gt");
  sweep->add_option("--jobs,-j", args->run.jobs,
                  "Runs at a time, each on its own thread (a run uses about one core; the results do not "
                  "depend on it)")
      ->check(WholeNumberIn(1, kMaxThreads))
      ->capture_default_str();
  sweep->add_option("--frames", args->run.frames, "Only the first N frames per pass (0 = all)")
      ->check(WholeNumberIn(0, kMaxFrames, "0 = all"));
  sweep->add_option("--cache", args->run.cache_dir, "Folder of cached datasets")->capture_default_str();
  sweep->add_option("--gl", args->run.gl, "Off-screen GL back-end for generation: osmesa or egl")->capture_default_str();
  sweep->add_flag("-q,--quiet", args->run.quiet, "No progress bars");

  CLI::App* merge = sweep->add_subcommand("merge", "Join the folders of a sweep run in shards into one report");
  merge->add_option("folders", merge_args->inputs, "The shards' sweep folders (the first one's sweep.json is the grid)")
      ->required();
  merge->add_option("--out,-o", merge_args->out_dir, "Where the merged report goes (default: the first folder)");
  merge->callback([merge_args, action] { *action = [merge_args] { return RunSweepMerge(*merge_args); }; });

  sweep->callback([sweep, args, action] {
    if (sweep->got_subcommand("merge")) return;
    if (args->file.empty()) throw CLI::RequiredError("file");
    *action = [args] { return RunSweep(*args); };
  });
}

}  // namespace segslam::harness
