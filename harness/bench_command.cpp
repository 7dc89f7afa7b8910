// `segslam bench render SCENARIO`: frames per second of the whole generation
// (render + noise + PNG encoding + writing) and of rendering alone, per GL back-end.
// `segslam bench slam SEQUENCE`: per-frame tracking time of the SLAM core, split by
// stage, and the local bundle adjustment time per keyframe.
// `segslam bench aliasing DATASET`: bench_aliasing_command.cpp.
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/statistics.h"
#include "core/tum_dataset.h"
#include "harness/cli_numbers.h"
#include "harness/commands.h"
#include "harness/dataset_run.h"
#include "harness/machine.h"
#include "harness/progress_bar.h"
#include "harness/slam_runner.h"
#include "slam/tracker.h"
#include "slam/tracker_options.h"
#include "scenes/scenario.h"
#include "seg/refiner_options.h"
#include "seg/simulated_segmenter.h"
#include "sim/dataset_generator.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <thread>
#include <unistd.h>

namespace segslam::harness {
namespace {

struct BenchRenderArgs {
  std::string scenario_file;
  std::vector<std::string> backends{"osmesa", "egl"};
  int frames = 150;
  std::string json_file;
  std::string work_dir;
};

struct BackendResult {
  std::string backend;
  std::string renderer;
  int frames = 0;
  double generation_fps = 0;
  double render_fps = 0;
};

int RunBenchRender(const BenchRenderArgs& args) {
  const scenes::Scenario scenario = scenes::LoadScenario(args.scenario_file);
  namespace fs = std::filesystem;
  const fs::path work = args.work_dir.empty() ? fs::temp_directory_path() : fs::path(args.work_dir);
  std::vector<BackendResult> results;
  for (const auto& name : args.backends) {
    const sim::GlBackend backend = sim::ParseGlBackend(name);
    BackendResult result;
    result.backend = name;

    // Whole generation, files included, into a scratch directory removed afterwards.
    const fs::path out = work / fmt::format("segslam-bench-{}-{}", name, ::getpid());
    sim::GenerateOptions options;
    options.backend = backend;
    options.max_frames_per_pass = args.frames;
    options.overwrite = true;
    ProgressBar bar(fmt::format("bench {} generation", name));
    const auto generation = sim::GenerateDataset(
        scenario, out, options, [&](const sim::GenerationProgress& p) {
          bar.Update(p.frames_done, p.frames_total, p.frames_per_second,
                     fmt::format("pass{}", p.pass_index + 1));
        });
    bar.Finish();
    fs::remove_all(out);
    result.frames = generation.frames;
    result.generation_fps = generation.FramesPerSecond();
    result.renderer = generation.gl_renderer;

    fmt::print(stderr, "bench {} render only ...\n", name);
    const auto render = sim::RenderOnly(scenario, backend, options.render, args.frames);
    result.render_fps = render.FramesPerSecond();
    results.push_back(result);
  }

  const nlohmann::json machine = MachineDescription();
  fmt::print("scenario {} ({}x{}), {} frames per back-end, on {}\n", scenario.name, scenario.camera.width,
             scenario.camera.height, results.empty() ? 0 : results[0].frames, MachineLine(machine));
  fmt::print("{:<8} {:>16} {:>16}  {}\n", "back-end", "generation fps", "render-only fps",
             "GL renderer");
  for (const auto& r : results) {
    fmt::print("{:<8} {:>16.1f} {:>16.1f}  {}\n", r.backend, r.generation_fps, r.render_fps,
               r.renderer);
  }
  if (!args.json_file.empty()) {
    nlohmann::json json = {
        {"scenario", scenario.name}, {"cores", std::thread::hardware_concurrency()}, {"machine", machine}};
    for (const auto& r : results) {
      json["backends"].push_back({{"backend", r.backend},
                                  {"renderer", r.renderer},
                                  {"frames", r.frames},
                                  {"generation_fps", r.generation_fps},
                                  {"render_only_fps", r.render_fps}});
    }
    WriteFileAtomically(args.json_file, json.dump(2) + "\n");
  }
  return 0;
}

struct BenchSlamArgs {
  std::string sequence;
  // What `segslam run` also takes: mode, masks, segmenter, seed, frames, camera, tracker
  // and refiner overrides (no --strength, --map-in or --map-out here).
  RunConfigWords words;
  DatasetRunOptions run;
  std::string json_file;
};

struct TimeSummary {
  double median = 0, p90 = 0, mean = 0;
};

TimeSummary Summarize(std::vector<double> values) {
  TimeSummary summary;
  if (values.empty()) return summary;
  std::sort(values.begin(), values.end());
  summary.median = Median(values);
  summary.p90 = values[std::min(values.size() - 1, static_cast<size_t>(0.9 * values.size()))];
  double sum = 0;
  for (double v : values) sum += v;
  summary.mean = sum / values.size();
  return summary;
}

int RunBenchSlam(const BenchSlamArgs& bench_args) {
  BenchSlamArgs args = bench_args;
  args.run.run = args.words.ToConfig("bench slam");
  SlamRunOptions options = SlamRunOptionsFor(args.run);
  options.read_ahead = false;
  if (!args.run.refiner_options.empty()) {
    if (!args.run.run.RefinesMasks()) {
      throw Error("bench slam: --refiner applies to the mutual loop: mode mutual with --segmenter or --masks");
    }
    if (std::string problem; !options.refiner.IsValid(&problem)) throw Error("bench slam: --refiner: " + problem);
  }
  // One core, as ORB-SLAM2's tracking thread: OpenCV's own threads would flatter us.
  cv::setNumThreads(1);
  const TumSequence sequence = TumSequence::OpenWithCameraFile(args.sequence, args.run.camera_file);
  const std::string mode = args.run.run.ModeName();
  ProgressBar bar("bench slam " + mode);
  const auto start = std::chrono::steady_clock::now();
  options.on_frame = [&](int done, int total) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    bar.Update(done, total, done / elapsed);
  };
  const SlamRunResult run = RunSlamOnSequence(sequence, options);
  bar.Finish();

  std::vector<std::pair<std::string, std::vector<double>>> stages = {
      {"features", {}}, {"coarse", {}}, {"judge", {}}, {"fine", {}}, {"map update", {}}, {"tracking total", {}}};
  std::vector<double> bundle_adjustment;
  for (const slam::FrameResult& frame : run.frames) {
    const slam::FrameTimings& t = frame.timings;
    const double values[] = {t.features_ms, t.coarse_ms, t.judge_ms, t.fine_ms, t.map_update_ms, t.TrackingMs()};
    for (size_t k = 0; k < stages.size(); ++k) stages[k].second.push_back(values[k]);
    if (frame.keyframe && t.bundle_adjustment_ms > 0) bundle_adjustment.push_back(t.bundle_adjustment_ms);
  }
  // The paper's loop also refines the segmenter's masks each frame; that is segmentation
  // work, reported beside tracking rather than in it.
  if (!run.refine_ms.empty()) stages.emplace_back("mask refinement", run.refine_ms);
  // The whole loop but the segmenter, frame by frame (the median of the sums, not the
  // sum of the medians).
  if (run.refine_ms.size() == run.frames.size() && !run.frames.empty()) {
    std::vector<double> loop;
    for (size_t i = 0; i < run.frames.size(); ++i) loop.push_back(run.frames[i].timings.TrackingMs() + run.refine_ms[i]);
    stages.emplace_back("loop (tracking+refinement)", loop);
  }
  // Per-frame times depend on the CPU (1.7x apart on two machines of the same kind): name it.
  const nlohmann::json machine = MachineDescription();
  const std::string masks = args.run.run.masks.Describe();
  fmt::print("sequence {} ({}x{}), mode {}, masks {}, {} frames, {} features requested, one core of {}\n",
             args.sequence, sequence.camera().intrinsics.width, sequence.camera().intrinsics.height, mode,
             masks, run.frames.size(), options.tracker.orb.max_features, MachineLine(machine));
  for (const auto& [what, overrides] :
       {std::pair{"tracker", args.run.tracker_options}, {"refiner", args.run.refiner_options}}) {
    if (!overrides.empty()) fmt::print("{} options: {}\n", what, fmt::join(overrides, " "));
  }
  fmt::print("{:<26} {:>10} {:>10} {:>10}\n", "stage (ms per frame)", "median", "p90", "mean");
  nlohmann::json json = {{"sequence", args.sequence},
                         {"mode", mode},
                         {"masks", masks},
                         {"frames", run.frames.size()},
                         {"features_requested", options.tracker.orb.max_features},
                         {"tracker_options", args.run.tracker_options},
                         {"refiner_options", args.run.refiner_options},
                         {"options", {{"tracker", slam::TrackerOptionRegistry().ToJson(options.tracker)}}},
                         {"machine", machine}};
  if (args.run.run.RefinesMasks()) json["options"]["refiner"] = seg::RefinerOptionRegistry().ToJson(options.refiner);
  for (const auto& [name, values] : stages) {
    const TimeSummary s = Summarize(values);
    fmt::print("{:<26} {:>10.2f} {:>10.2f} {:>10.2f}\n", name, s.median, s.p90, s.mean);
    json["stages_ms"][name] = {{"median", s.median}, {"p90", s.p90}, {"mean", s.mean}};
  }
  const TimeSummary ba = Summarize(bundle_adjustment);
  fmt::print("{:<26} {:>10.2f} {:>10.2f} {:>10.2f}  ({} keyframes)\n", "bundle adj. per keyframe", ba.median,
             ba.p90, ba.mean, bundle_adjustment.size());
  json["bundle_adjustment_per_keyframe_ms"] = {
      {"median", ba.median}, {"p90", ba.p90}, {"mean", ba.mean}, {"keyframes", bundle_adjustment.size()}};
  if (!args.json_file.empty()) WriteFileAtomically(args.json_file, json.dump(2) + "\n");
  return 0;
}

}  // namespace

void AddBenchCommand(CLI::App& app, std::function<int()>* action) {
  CLI::App* bench = app.add_subcommand("bench", "Measure speed, and how alike distant places look");
  bench->require_subcommand(1);
  auto args = std::make_shared<BenchRenderArgs>();
  CLI::App* render = bench->add_subcommand(
      "render", "Frames per second of dataset generation and of rendering alone, per GL back-end");
  render->add_option("scenario", args->scenario_file, "Scenario YAML file")->required();
  render->add_option("--gl", args->backends, "Back-ends to measure (osmesa, egl)")
      ->delimiter(',')
      ->capture_default_str();
  render->add_option("--frames", args->frames, "Frames per pass (0 = all)")
      ->check(WholeNumberIn(0, kMaxFrames, "0 = all"))
      ->capture_default_str();
  render->add_option("--json", args->json_file, "Also write the results as JSON");
  render->add_option("--work-dir", args->work_dir, "Scratch directory (default: system temp)");
  render->callback([args, action] { *action = [args] { return RunBenchRender(*args); }; });

  auto slam_args = std::make_shared<BenchSlamArgs>();
  CLI::App* slam = bench->add_subcommand(
      "slam", "Per-frame tracking time of the SLAM core by stage, and bundle adjustment per keyframe");
  slam->add_option("sequence", slam_args->sequence,
                   "A TUM-layout sequence (with masks/ for mutual and mask-moveable, unless --masks names a folder)")
      ->required();
  slam->add_option("--mode", slam_args->words.mode, "plain, mask-moveable, mutual, mutual-sparse or oracle")
      ->check(CLI::IsMember(mutual::SlamModeNames()))
      ->capture_default_str();
  slam->add_option("--frames", slam_args->run.frames, "Only the first N frames (0 = all)")
      ->check(WholeNumberIn(0, kMaxFrames, "0 = all"));
  slam->add_option("--masks", slam_args->words.masks,
                   "'gt' (the sequence's masks/) or a folder of external masks (mutual: refined in the loop)")
      ->capture_default_str();
  slam->add_option("--segmenter", slam_args->words.segmenter,
                   "Simulated segmenter preset on the sequence's ground-truth masks (mutual: refined in the loop)")
      ->check(CLI::IsMember(seg::SimulatedSegmenterOptions::PresetNames()));
  slam->add_option("--seed", slam_args->words.seed, "Seed of the simulated segmenter")->capture_default_str();
  slam->add_option("--json", slam_args->json_file, "Also write the results as JSON");
  slam->add_option("--camera", slam_args->run.camera_file,
                   "camera.yaml to use instead of the sequence's own (for a real sequence without one)");
  slam->add_option("--tracker", slam_args->run.tracker_options,
                   "Override a tracker option, NAME=VALUE (repeatable; `segslam options tracker` lists them), e.g. orb.max_features=2000");
  slam->add_option("--refiner", slam_args->run.refiner_options,
                   "Override a refinement option of the mutual loop, NAME=VALUE (repeatable; `segslam options refiner` lists them)");
  slam->callback([slam_args, action] { *action = [slam_args] { return RunBenchSlam(*slam_args); }; });

  AddBenchAliasingCommand(*bench, action);
}

}  // namespace segslam::harness
