// `segslam bench render SCENARIO`: frames per second of the whole generation
// (render + noise + PNG encoding + writing) and of rendering alone, per GL back-end.
#include "core/atomic_file.h"
#include "core/error.h"
#include "harness/commands.h"
#include "harness/progress_bar.h"
#include "scenes/scenario.h"
#include "sim/dataset_generator.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <memory>
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

  fmt::print("scenario {} ({}x{}), {} frames per back-end, {} cores\n", scenario.name,
             scenario.camera.width, scenario.camera.height, results.empty() ? 0 : results[0].frames,
             std::thread::hardware_concurrency());
  fmt::print("{:<8} {:>16} {:>16}  {}\n", "back-end", "generation fps", "render-only fps",
             "GL renderer");
  for (const auto& r : results) {
    fmt::print("{:<8} {:>16.1f} {:>16.1f}  {}\n", r.backend, r.generation_fps, r.render_fps,
               r.renderer);
  }
  if (!args.json_file.empty()) {
    nlohmann::json json = {{"scenario", scenario.name}, {"cores", std::thread::hardware_concurrency()}};
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

}  // namespace

void AddBenchCommand(CLI::App& app, std::function<int()>* action) {
  CLI::App* bench = app.add_subcommand("bench", "Measure speed");
  bench->require_subcommand(1);
  auto args = std::make_shared<BenchRenderArgs>();
  CLI::App* render = bench->add_subcommand(
      "render", "Frames per second of dataset generation and of rendering alone, per GL back-end");
  render->add_option("scenario", args->scenario_file, "Scenario YAML file")->required();
  render->add_option("--gl", args->backends, "Back-ends to measure (osmesa, egl)")
      ->delimiter(',')
      ->capture_default_str();
  render->add_option("--frames", args->frames, "Frames per pass (0 = all)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  render->add_option("--json", args->json_file, "Also write the results as JSON");
  render->add_option("--work-dir", args->work_dir, "Scratch directory (default: system temp)");
  render->callback([args, action] { *action = [args] { return RunBenchRender(*args); }; });
}

}  // namespace segslam::harness
