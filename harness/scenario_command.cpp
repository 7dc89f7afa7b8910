// `segslam scenario run SCENARIO.yaml`: the CI entry point. Generates the scenario's
// dataset once (cached by a hash of the effective scenario, the frame limit and the code
// version), runs each mode `repeats` times (repeats differ by the simulated segmenter's
// seed; SLAM itself is deterministic, so a mode without a segmenter runs once), scores
// each run (harness/run_evaluation.h), checks the scenario's `expect:` thresholds on the
// medians over repeats (harness/scenario_expectations.h names the metrics) and writes the
// report directory:
//   results.json  every run's metrics, the medians/min/max, the checks, the scenario,
//                 seeds, code version and machine
//   report.md, report.html  the tables in the layout of the paper's
//   scenario.yaml           the effective scenario (every key, overrides applied)
//   figures/                top views of both passes (the paper's Fig. 4), raw vs refined
//                           masks (Fig. 5) and features kept vs dropped (Fig. 6)
//   runs/<mode>/<seed>/     each run's outputs, as `segslam run` writes them
// Exit code: 0 when every expectation passes, 2 when one fails, 1 on an error.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <atomic>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_file.h"
#include "core/tum_dataset.h"
#include "harness/cli_numbers.h"
#include "harness/commands.h"
#include "harness/dataset_cache.h"
#include "harness/dataset_run.h"
#include "harness/interrupt.h"
#include "harness/progress_bar.h"
#include "harness/run_evaluation.h"
#include "harness/scenario_figures.h"
#include "harness/scenario_report.h"
#include "harness/scenario_runner.h"
#include "scenes/scenario.h"
#include "sim/dataset_generator.h"
#include "segslam_version.h"  // generated at build time: SEGSLAM_VERSION

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

constexpr int kExitExpectationFailed = 2;

using ScenarioRunArgs = ScenarioRunRequest;

std::string Metres(const std::optional<ErrorStatistics>& ate) {
  return ate.has_value() ? fmt::format("{:.4f} m", ate->rmse) : "n/a";
}

// The line printed when a run ends, e.g. "[3/7] mutual        seed 2   pass1 ATE ...".
std::string RunLine(const ScenarioRunRequest& args, int done_runs, int total_runs, const RepeatRun& run,
                    bool deterministic) {
  std::string line = fmt::format("{}[{}/{}] {:<13} {:<7}", args.progress_prefix, done_runs, total_runs, run.mode,
                                 deterministic ? "" : fmt::format("seed {}", run.seed));
  for (const PassEvaluation& pass : run.evaluation.passes) {
    line += fmt::format("  {} ATE {} localized {:.0f}%", pass.name, Metres(pass.ate_m), 100 * pass.LocalizedShare());
  }
  return fmt::format("{}  ({:.1f} s)", line, run.seconds);
}

// Runs each of a scenario's runs on the dataset (segslam run, then eval), args.jobs at a
// time, and fills in its seconds and evaluation. A run is deterministic and uses one
// thread (plus OpenCV's), so the results do not depend on how many run at once or in
// which order they end. One job shows a progress bar per pass; several share one bar
// over all frames. The first error stops the other runs and is rethrown.
class RepeatRunner {
 public:
  RepeatRunner(std::vector<RepeatRun>* runs, const BenchSettings& bench, const fs::path& dataset,
               const fs::path& report_dir, const ScenarioRunRequest& args, const std::atomic<bool>* cancel)
      : runs_(*runs),
        bench_(bench),
        dataset_(dataset),
        report_dir_(report_dir),
        args_(args),
        cancel_(cancel),
        total_runs_(static_cast<int>(runs->size())),
        jobs_(std::clamp(args.jobs, 1, std::max(1, total_runs_))),
        frames_done_(runs->size(), 0) {
    // The shared bar counts frames over all runs: every run reads the same passes.
    for (const char* pass : {"pass1", "pass2"}) {
      const int frames = static_cast<int>(TumSequence::Open(dataset / pass).size());
      frames_per_run_ += args.frames > 0 ? std::min(frames, args.frames) : frames;
    }
    if (jobs_ > 1 && !args.quiet) {
      shared_bar_.emplace(fmt::format("{}{} runs, {} at a time", args.progress_prefix, total_runs_, jobs_));
    }
  }

  void RunAll() {
    std::vector<std::thread> threads;
    for (int j = 1; j < jobs_; ++j) threads.emplace_back([this] { Work(); });
    Work();
    for (std::thread& thread : threads) thread.join();
    if (shared_bar_.has_value()) shared_bar_->Finish();
    if (first_error_) std::rethrow_exception(first_error_);
  }

 private:
  // Takes the next run until none is left or a run has failed.
  void Work() {
    for (std::size_t index; !stop_.load() && (index = next_.fetch_add(1)) < runs_.size();) {
      try {
        RunOne(index);
      } catch (...) {
        std::lock_guard<std::mutex> lock(output_);
        if (!first_error_) first_error_ = std::current_exception();
        stop_ = true;
      }
    }
  }

  void RunOne(std::size_t index) {
    RepeatRun& run = runs_[index];
    DatasetRunOptions options;
    options.run = bench_.RunConfigFor(run.mode, run.seed);
    if (options.run.RefinesMasks()) options.refiner_options = bench_.refiner;
    options.tracker_options = bench_.TrackerAssignmentsFor(run.repeat);
    std::optional<ProgressBar> bar;  // this run's, with one job
    std::string bar_pass;
    int pass1_frames = 0;
    // Each pass's rate counts from the end of the previous pass (or the run's start).
    auto pass_start = std::chrono::steady_clock::now();
    options.on_frame = [&](const std::string& pass, int done, int total) {
      if (cancel_->load()) throw Error("scenario run: cancelled");
      if (stop_.load()) throw Error("scenario run: stopped after another run's error");
      if (args_.quiet) return;
      const auto now = std::chrono::steady_clock::now();
      if (jobs_ > 1) {
        if (pass == "pass1") pass1_frames = total;
        UpdateSharedBar(index, (pass == "pass1" ? 0 : pass1_frames) + done, done == total, now);
        return;
      }
      if (!bar.has_value() || bar_pass != pass) {
        if (bar.has_value()) bar->Finish();
        bar.emplace(fmt::format("{}[{}/{}] {} {}", args_.progress_prefix, index + 1, total_runs_, run.mode, pass));
        bar_pass = pass;
      }
      bar->Update(done, total, done / std::max(std::chrono::duration<double>(now - pass_start).count(), 1e-9));
      if (done == total) pass_start = now;
    };
    const auto run_start = std::chrono::steady_clock::now();
    RunDataset(dataset_, report_dir_ / run.run_dir, options);
    if (bar.has_value()) bar->Finish();
    run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - run_start).count();
    run.evaluation = EvaluateRun(report_dir_ / run.run_dir, dataset_);
    std::lock_guard<std::mutex> lock(output_);
    ++done_runs_;
    if (shared_bar_.has_value()) shared_bar_->Finish();
    fmt::print("{}\n", RunLine(args_, done_runs_, total_runs_, run, bench_.ModeIsDeterministic(run.mode)));
    std::fflush(stdout);  // a CI log shows each run as it ends
  }

  // Run `index` has read `frames` frames of both passes; redrawn at most every 0.2 s
  // and at the end of a pass.
  void UpdateSharedBar(std::size_t index, int frames, bool pass_done, std::chrono::steady_clock::time_point now) {
    std::lock_guard<std::mutex> lock(output_);
    frames_done_[index] = frames;
    if (now - last_draw_ < std::chrono::milliseconds(200) && !pass_done) return;
    last_draw_ = now;
    int all_done = 0;
    for (int done : frames_done_) all_done += done;
    const double seconds = std::max(std::chrono::duration<double>(now - start_).count(), 1e-9);
    shared_bar_->Update(all_done, frames_per_run_ * total_runs_, all_done / seconds,
                        fmt::format("{} of {} runs done", done_runs_, total_runs_));
  }

  std::vector<RepeatRun>& runs_;
  const BenchSettings& bench_;
  const fs::path& dataset_;
  const fs::path& report_dir_;
  const ScenarioRunRequest& args_;
  const std::atomic<bool>* cancel_;
  const int total_runs_;
  const int jobs_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::atomic<std::size_t> next_{0};
  std::atomic<bool> stop_{false};

  std::mutex output_;  // guards printing, the shared bar and everything below
  int frames_per_run_ = 0;
  std::vector<int> frames_done_;  // per run, both passes
  std::optional<ProgressBar> shared_bar_;
  std::chrono::steady_clock::time_point last_draw_ = start_;
  int done_runs_ = 0;
  std::exception_ptr first_error_;
};

std::string EffectiveYaml(const scenes::Scenario& scenario) {
  YAML::Emitter yaml;
  yaml << scenes::ScenarioToYaml(scenario);
  return yaml.c_str();
}

}  // namespace

BenchSettings EffectiveBench(const scenes::Scenario& scenario, const ScenarioRunRequest& request) {
  BenchSettings bench = BenchSettings::FromYaml(scenario.bench, request.scenario_file);
  if (!request.modes.empty()) {
    bench.modes.clear();
    std::string rest = request.modes;
    for (std::size_t comma; (comma = rest.find(',')) != std::string::npos; rest = rest.substr(comma + 1)) {
      bench.modes.push_back(rest.substr(0, comma));
    }
    bench.modes.push_back(rest);
  }
  if (request.repeats > 0) bench.repeats = request.repeats;
  if (!request.segmenter.empty()) {
    bench.segmenter = request.segmenter;
    if (bench.segmenter == "gt") {  // nothing to scale or refine: the file's settings for its segmenter go
      bench.segmenter_strength = 1.0;
      bench.refiner.clear();
    }
  }
  if (const std::string problem = bench.Check(); !problem.empty()) throw Error("scenario run: " + problem);
  return bench;
}

namespace {

// The expectations this run can check: those whose modes all run (--modes may leave some
// of the scenario's modes out). The others' names go to *skipped.
std::vector<Expectation> CheckableExpectations(std::vector<Expectation> expectations, const BenchSettings& bench,
                                               std::vector<std::string>* skipped) {
  const auto mode_runs = [&](const std::string& mode) {
    return mode.empty() || std::find(bench.modes.begin(), bench.modes.end(), mode) != bench.modes.end();
  };
  for (auto it = expectations.begin(); it != expectations.end();) {
    const bool against_plain = it->name.metric == kTrafficErrorRemoved;
    if (mode_runs(it->name.mode) && mode_runs(it->name.denominator_mode) && (!against_plain || mode_runs("plain"))) {
      ++it;
    } else {
      skipped->push_back(it->name.text);
      it = expectations.erase(it);
    }
  }
  return expectations;
}

// True when `file` is the results.json of a segslam scenario report (one made before
// report folders were marked).
bool IsReportResults(const fs::path& file) {
  try {
    const nlohmann::json results = ReadJsonFile(file);
    return results.is_object() && results.contains("code_version") && results.contains("runs") &&
           results.contains("expectations");
  } catch (const Error&) {
    return false;
  }
}

// A report folder is marked as one when a run first writes to it. Its earlier report is
// replaced (runs/ and figures/ removed whole), so a folder with other contents and no
// mark, nor the results.json of a report made before marks were kept, is refused rather
// than emptied; so is the folder of the scenario file itself, whose scenario.yaml the
// report would replace.
void ClaimReportFolder(const fs::path& report_dir, const fs::path& scenario_file) {
  const fs::path mark = report_dir / ".segslam-report";
  if (fs::exists(report_dir) && !fs::is_empty(report_dir) && !fs::exists(mark) &&
      !IsReportResults(report_dir / "results.json")) {
    throw FileError(report_dir,
                    "holds other files and no segslam scenario report, which a run would replace; choose another --out");
  }
  std::error_code error;
  if (fs::equivalent(report_dir / "scenario.yaml", scenario_file, error)) {
    throw FileError(report_dir, "holds the scenario file itself as scenario.yaml, which the report would replace; "
                                "choose another --out");
  }
  fs::create_directories(report_dir);
  WriteFileAtomically(mark, "A segslam scenario report: `segslam scenario run` replaces what is here.\n");
}

// --junit names the file to write: a folder there, empty or not, is refused (never
// removed), and the file's folder is made now rather than found missing after the runs.
void PrepareJUnitPath(const fs::path& junit_file) {
  std::error_code error;
  if (fs::is_directory(junit_file, error)) {
    throw FileError(junit_file, "is a folder; --junit takes the path of the JUnit XML file to write, e.g. " +
                                    (junit_file / "junit.xml").string());
  }
  if (junit_file.has_parent_path()) {
    fs::create_directories(junit_file.parent_path(), error);
    if (error) throw FileError(junit_file.parent_path(), "cannot make the folder of --junit: " + error.message());
  }
}

// The scenario's dataset in `dataset`, generated once per effective scenario and code
// version. The generator writes into a staging folder and renames it, so an existing
// folder was complete; it is checked against its manifest.json before reuse
// (CheckCachedDataset) and generated anew if a file has changed since. Processes that
// share the cache (sweep shards, array tasks on several nodes) generate it once: the
// others wait for the one that holds its lock and reuse its dataset. Returns whether it
// was there already, or made by another process, and intact.
bool EnsureDataset(const scenes::Scenario& scenario, const fs::path& dataset, const ScenarioRunRequest& args,
                   sim::GlBackend backend, const std::atomic<bool>* cancel) {
  bool damaged = false;
  if (IsTwoPassDataset(dataset)) {
    // A file edited, cut or deleted since generation would be read as the scenario's.
    const CachedDatasetCheck check = CheckCachedDataset(dataset, args.verify);
    if (check.problems.empty()) {
      fmt::print("dataset {} (cached; {} manifest.json in {:.1f} s)\n", dataset.string(),
                 check.hashed ? "sizes and SHA-256s match its" : "sizes match its", check.seconds);
      std::fflush(stdout);
      RecordCachedDataset(dataset, scenario.name, args.frames, SEGSLAM_VERSION);
      return true;
    }
    fmt::print("dataset {} (cached) differs from its manifest.json in {} file(s), e.g. {}; generating it anew\n",
               dataset.string(), check.problems.size(), check.problems.front());
    std::fflush(stdout);
    damaged = true;
  }
  // Another process's dataset counts once it is there and intact; a damaged one found
  // above, until its manifest is replaced.
  const fs::path manifest = dataset / "manifest.json";
  std::error_code time_error;
  const fs::file_time_type damaged_manifest_time = damaged ? fs::last_write_time(manifest, time_error) : fs::file_time_type();
  const auto made_by_another = [&] {
    if (!IsTwoPassDataset(dataset)) return false;
    std::error_code error;
    if (damaged && fs::last_write_time(manifest, error) == damaged_manifest_time) return false;
    return CheckCachedDataset(dataset).problems.empty();
  };
  const auto generate = [&] {
    sim::GenerateOptions generate_options;
    generate_options.backend = backend;
    generate_options.max_frames_per_pass = args.frames;
    generate_options.cancel = cancel;
    // Replaces a dataset there (one that failed its check); a folder that is no dataset
    // is refused (core/output_folders.h).
    generate_options.overwrite = true;
    // One another process finished meanwhile (its lock broken as stale) is kept; not the
    // damaged one just found.
    generate_options.keep_complete_dataset = !damaged;
    ProgressBar bar(args.progress_prefix + "generate " + scenario.name);
    const sim::GenerateSummary summary =
        sim::GenerateDataset(scenario, dataset, generate_options, [&](const sim::GenerationProgress& p) {
          if (!args.quiet) bar.Update(p.frames_done, p.frames_total, p.frames_per_second, fmt::format("pass{}", p.pass_index + 1));
        });
    if (!args.quiet) bar.Finish();
    fmt::print("dataset {}: generated {} frames in {:.1f} s{}\n", dataset.string(), summary.frames, summary.seconds,
               summary.kept_existing ? " (another process finished it first: that one is kept)" : "");
  };
  const std::string key = dataset.filename().string();
  const DatasetOrigin origin = GenerateUnlessAnotherProcessDoes(dataset, key, false, made_by_another, generate, cancel);
  if (origin == DatasetOrigin::kMadeByAnotherProcess) {
    fmt::print("dataset {} (generated by another process meanwhile; its files match its manifest.json): reused\n",
               dataset.string());
    std::fflush(stdout);
  }
  // Written on every use: its key names this build, so a dataset from before records
  // were kept gets one too.
  RecordCachedDataset(dataset, scenario.name, args.frames, SEGSLAM_VERSION);
  return origin == DatasetOrigin::kMadeByAnotherProcess;
}

// Every run, in report order: each mode `repeats` times, a deterministic mode once.
std::vector<RepeatRun> PlanRuns(const BenchSettings& bench) {
  std::vector<RepeatRun> runs;
  for (const std::string& mode : bench.modes) {
    const bool deterministic = bench.ModeIsDeterministic(mode);
    if (deterministic && bench.repeats > 1) {
      fmt::print("{}: deterministic ({}), so one run stands for all {} repeats\n", mode,
                 mode == "plain" ? "no segmenter" : "ground-truth masks", bench.repeats);
    }
    const int repeats = deterministic ? 1 : bench.repeats;
    for (int repeat = 0; repeat < repeats; ++repeat) {
      RepeatRun run;
      run.mode = mode;
      run.repeat = repeat;
      run.seed = bench.seed + static_cast<std::uint64_t>(repeat);
      run.run_dir = (fs::path("runs") / mode / (deterministic ? std::string("once") : fmt::format("seed{}", run.seed))).string();
      runs.push_back(std::move(run));
    }
  }
  return runs;
}

}  // namespace

ScenarioReport RunScenarioToReport(const ScenarioRunRequest& args) {
  const auto start = std::chrono::steady_clock::now();
  // Everything that can be refused is checked before any work starts.
  scenes::Scenario scenario = scenes::LoadScenario(args.scenario_file);
  try {
    scenes::ApplyOverrides(scenario, args.overrides);
  } catch (const Error& e) {
    throw Error(std::string("--set ") + e.what());
  }
  // Thresholds are checked against the scenario's own modes (a mode it never runs is an
  // error in the file); --modes may then leave some of them out for this run.
  std::vector<Expectation> expectations = ParseExpectations(
      scenario.expect, BenchSettings::FromYaml(scenario.bench, args.scenario_file).modes, args.scenario_file);
  const BenchSettings bench = EffectiveBench(scenario, args);
  for (const Expectation& expectation : expectations) {
    if (expectation.name.metric == kTrafficErrorRemoved && !bench.static_twin) {
      throw Error(args.scenario_file + ": expect: " + expectation.name.text +
                  " needs the static twin (bench: {static_twin: true}, or --set bench.static_twin=true)");
    }
  }
  std::vector<std::string> skipped;
  expectations = CheckableExpectations(std::move(expectations), bench, &skipped);
  const sim::GlBackend backend = sim::ParseGlBackend(args.gl);
  const std::atomic<bool>* cancel = InstallInterruptFlag();

  const fs::path report_dir = args.out_dir.empty() ? fs::path("reports") / scenario.name : fs::path(args.out_dir);
  const fs::path dataset = fs::path(args.cache_dir) / (scenario.name + "-" + DatasetCacheKey(scenario, args.frames, backend));
  fmt::print("segslam scenario run: {} ({}), modes {}, {} repeat(s), segmenter {}\n", scenario.name,
             args.scenario_file, fmt::format("{}", fmt::join(bench.modes, ", ")), bench.repeats, bench.SegmenterLabel());
  for (const std::string& name : skipped) fmt::print("expectation {} not checked: --modes leaves its mode out\n", name);

  std::fflush(stdout);
  if (!args.junit_file.empty()) PrepareJUnitPath(args.junit_file);
  ClaimReportFolder(report_dir, args.scenario_file);
  // An earlier report in the same place goes first (before a generation that may fail or
  // be interrupted), so a run that stops half-way leaves no results.json or JUnit file
  // that looks complete.
  for (const char* stale : {"results.json", "report.md", "report.html", "scenario.yaml"}) fs::remove(report_dir / stale);
  if (!args.junit_file.empty()) fs::remove(args.junit_file);
  fs::remove_all(report_dir / "runs");
  fs::remove_all(report_dir / "figures");
  ScenarioReport report;
  report.dataset_from_cache = EnsureDataset(scenario, dataset, args, backend, cancel);
  // Datasets of older builds have no count: none were left out then.
  const nlohmann::json extra =
      ReadJsonFile(dataset / "manifest.json").value("extra", nlohmann::json::object());
  report.movers_left_out = extra.value("movers_left_out", 0);
  report.red_lights_left_out = extra.value("red_lights_left_out", 0);
  fs::create_directories(report_dir / "runs");
  std::vector<RepeatRun> runs = PlanRuns(bench);
  std::fflush(stdout);
  RepeatRunner(&runs, bench, dataset, report_dir, args, cancel).RunAll();
  report.runs = std::move(runs);
  // A Ctrl-C after the last frame stops here, not after minutes of figures with exit 0.
  if (cancel->load()) throw Error("scenario run: interrupted; no report written to " + report_dir.string());
  if (bench.static_twin) {
    // Plain on the same world with nothing moving: how much error the traffic adds.
    const scenes::Scenario twin = scenes::StaticTwin(scenario);
    const fs::path twin_dataset =
        fs::path(args.cache_dir) / (twin.name + "-" + DatasetCacheKey(twin, args.frames, backend));
    fmt::print("static twin: {} (no moving cars, pedestrians or walkers)\n", twin.name);
    EnsureDataset(twin, twin_dataset, args, backend, cancel);
    BenchSettings twin_bench = bench;
    twin_bench.modes = {"plain"};
    // Plain is deterministic unless the feature budget is jittered; then the twin runs
    // with each repeat's budget too.
    if (bench.feature_jitter == 0) twin_bench.repeats = 1;
    report.static_twin_runs = PlanRuns(twin_bench);
    for (RepeatRun& run : report.static_twin_runs) {
      run.run_dir = (fs::path("runs") / kStaticTwinPlain / fs::path(run.run_dir).filename()).string();
    }
    RepeatRunner(&report.static_twin_runs, twin_bench, twin_dataset, report_dir, args, cancel).RunAll();
    if (cancel->load()) throw Error("scenario run: interrupted; no report written to " + report_dir.string());
    report.static_twin_dataset_dir = twin_dataset.string();
  }

  report.scenario_name = scenario.name;
  report.scenario_file = args.scenario_file;
  report.effective_scenario_yaml = EffectiveYaml(scenario);
  report.overrides = args.overrides;
  report.code_version = SEGSLAM_VERSION;
  report.dataset_dir = dataset.string();
  report.frames_per_pass = args.frames;
  report.bench = bench;
  report.spreads = Summarize(report.runs);
  for (const auto& [pass, modes] : Summarize(report.static_twin_runs)) {
    for (const auto& [mode, metrics] : modes) report.spreads[pass][kStaticTwinPlain] = metrics;
  }
  report.checks = CheckExpectations(expectations, report.spreads);
  report.not_checked = skipped;
  report.report_dir = report_dir;
  // Figures before the documents, which show each figure that exists.
  for (const std::string& problem : DrawReportFigures(report)) fmt::print("figure not drawn: {}\n", problem);
  if (cancel->load()) throw Error("scenario run: interrupted; no report written to " + report_dir.string());
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  WriteFileAtomically(report_dir / "scenario.yaml", report.effective_scenario_yaml + "\n");
  WriteFileAtomically(report_dir / "results.json", report.ToJson().dump(2) + "\n");
  WriteFileAtomically(report_dir / "report.md", report.ToMarkdown());
  WriteFileAtomically(report_dir / "report.html", report.ToHtml());
  if (!args.junit_file.empty()) WriteFileAtomically(args.junit_file, report.ToJUnitXml());
  return report;
}

namespace {

int RunScenario(const ScenarioRunArgs& args) {
  const ScenarioReport report = RunScenarioToReport(args);
  const std::string& scenario_name = report.scenario_name;
  const fs::path& report_dir = report.report_dir;
  fmt::print("{}", report.ToText());
  int failed = 0;
  if (!report.checks.empty() || !report.not_checked.empty()) fmt::print("\nexpectations (medians over repeats):\n");
  for (const ExpectationResult& check : report.checks) {
    fmt::print("  {}  {:<40} {:>12} {}\n", check.passed ? "PASS" : "FAIL", check.expectation.name.text,
               std::isnan(check.value) ? std::string("n/a") : fmt::format("{:.6g}", check.value),
               check.expectation.Bounds());
    if (!check.passed) ++failed;
  }
  for (const std::string& name : report.not_checked) fmt::print("  SKIP  {:<40} --modes leaves its mode out\n", name);
  const std::string not_checked =
      report.not_checked.empty() ? std::string() : fmt::format(", {} not checked", report.not_checked.size());
  fmt::print("scenario {}: {} of {} expectations passed{}, {} runs in {:.1f} s, report in {}\n", scenario_name,
             report.checks.size() - failed, report.checks.size(), not_checked, report.runs.size(), report.seconds,
             report_dir.string());
  if (report.checks.empty() && !report.not_checked.empty()) {
    fmt::print("scenario {}: no expectation was checked (--modes leaves out a mode of each); that is not a pass\n",
               scenario_name);
  }
  return report.Passed() ? 0 : kExitExpectationFailed;
}

struct PruneCacheArgs {
  std::string cache_dir = "data/cache";
  bool dry_run = false;
};

std::string Gigabytes(std::uintmax_t bytes) { return fmt::format("{:.2f} GB", bytes / 1e9); }

int RunPruneCache(const PruneCacheArgs& args) {
  const std::vector<CachedDataset> entries = ListDatasetCache(args.cache_dir);
  if (entries.empty()) {
    fmt::print("{}: no cached datasets\n", args.cache_dir);
    return 0;
  }
  fmt::print("{:<48} {:>10}  {:<28} {}\n", "dataset", "size", "generated by", "");
  std::uintmax_t stale_bytes = 0, kept_bytes = 0;
  int stale = 0, kept = 0;
  for (const CachedDataset& entry : entries) {
    const bool remove = IsStale(entry, SEGSLAM_VERSION);
    const std::string by = entry.leftover              ? "(an interrupted generation)"
                           : entry.code_version.empty() ? "(no record)"
                                                        : entry.code_version;
    if (remove && !args.dry_run) RemoveCachedDataset(entry);
    fmt::print("{:<48} {:>10}  {:<28} {}\n", entry.dir.filename().string(), Gigabytes(entry.bytes), by,
               !remove ? "kept (this build)" : args.dry_run ? "would be removed" : "removed");
    (remove ? stale : kept) += 1;
    (remove ? stale_bytes : kept_bytes) += entry.bytes;
  }
  fmt::print("prune-cache: {} {} dataset(s), {}; kept {} of this build ({}), {}\n",
             args.dry_run ? "would remove" : "removed", stale, Gigabytes(stale_bytes), kept, Gigabytes(kept_bytes),
             SEGSLAM_VERSION);
  return 0;
}

}  // namespace

void AddScenarioCommand(CLI::App& app, std::function<int()>* action) {
  CLI::App* scenario = app.add_subcommand("scenario", "Scenario files as tests: generate, run every mode, check thresholds");
  scenario->require_subcommand(1);
  auto args = std::make_shared<ScenarioRunArgs>();
  CLI::App* run = scenario->add_subcommand(
      "run",
      "Generate the scenario's dataset (cached), run each mode repeatedly, score the runs, check the scenario's "
      "expect: thresholds on the medians and write results.json, report.md and report.html. Exit code 0: all "
      "thresholds pass; 2: one fails; 1: an error");
  run->add_option("scenario", args->scenario_file, "Scenario YAML file (with optional expect: and bench: sections)")
      ->required();
  run->add_option("--out,-o", args->out_dir, "Report directory (default reports/<scenario name>)");
  run->add_option("--repeats", args->repeats, "Runs per mode, seeds bench.seed.. (default: bench.repeats, else 10)")
      ->check(WholeNumberIn(1, kMaxRepeats));
  run->add_option("--modes", args->modes, "Comma-separated modes (default: bench.modes, else plain,mask-moveable,mutual)");
  run->add_option("--segmenter", args->segmenter,
                  "Simulated segmenter preset for mask-moveable and mutual, or gt (default: bench.segmenter, else "
                  "fcis-like)");
  run->add_option("--jobs,-j", args->jobs,
                "Runs at a time, each on its own thread (a run uses about one core; the results do not "
                "depend on it)")
      ->check(WholeNumberIn(1, kMaxThreads))
      ->capture_default_str();
  run->add_option("--frames", args->frames, "Generate and run only the first N frames per pass (0 = all)")
      ->check(WholeNumberIn(0, kMaxFrames, "0 = all"));
  run->add_option("--junit", args->junit_file, "Also write JUnit XML, one testcase per expectation");
  run->add_option("--cache", args->cache_dir, "Folder of cached datasets (<name>-<hash> inside)")->capture_default_str();
  run->add_option("--set", args->overrides, "Override a scenario key, e.g. --set city.moving_cars=8 (repeatable)");
  run->add_option("--gl", args->gl, "Off-screen GL back-end for generation: osmesa or egl")->capture_default_str();
  run->add_flag("--verify", args->verify,
                "Compare every file of a cached dataset with its manifest.json's SHA-256 (by default sizes each time, "
                "hashes on a process's first use)");
  run->add_flag("-q,--quiet", args->quiet, "No progress bars");
  run->callback([args, action] { *action = [args] { return RunScenario(*args); }; });
  AddSuiteCommand(*scenario, action);

  auto prune_args = std::make_shared<PruneCacheArgs>();
  CLI::App* prune = scenario->add_subcommand(
      "prune-cache",
      "Remove the cached datasets this build no longer uses: those another build generated (each build keys its "
      "own), those without a record of their build, and what interrupted generations left");
  prune->add_option("--cache", prune_args->cache_dir, "Folder of cached datasets (<name>-<hash> inside)")
      ->capture_default_str();
  prune->add_flag("--dry-run", prune_args->dry_run, "List what would be removed, remove nothing");
  prune->callback([prune_args, action] { *action = [prune_args] { return RunPruneCache(*prune_args); }; });
}

}  // namespace segslam::harness
