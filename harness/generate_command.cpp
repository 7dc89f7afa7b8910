// `segslam generate SCENARIO --out DIR`: renders the scenario's two passes into a dataset.
#include "core/error.h"
#include "harness/commands.h"
#include "harness/interrupt.h"
#include "harness/progress_bar.h"
#include "scenes/scenario.h"
#include "sim/dataset_generator.h"

#include <fmt/format.h>

#include <memory>

namespace segslam::harness {
namespace {

struct GenerateArgs {
  std::string scenario_file;
  std::string out_dir;
  std::string gl = "osmesa";
  int frames = 0;
  int threads = 0;
  bool force = false;
  bool quiet = false;
  std::vector<std::string> overrides;
};

int RunGenerate(const GenerateArgs& args) {
  scenes::Scenario scenario = scenes::LoadScenario(args.scenario_file);
  try {
    scenes::ApplyOverrides(scenario, args.overrides);
  } catch (const Error& e) {
    throw Error(std::string("--set ") + e.what());
  }

  sim::GenerateOptions options;
  options.backend = sim::ParseGlBackend(args.gl);
  options.max_frames_per_pass = args.frames;
  options.encode_threads = args.threads;
  options.overwrite = args.force;
  options.cancel = InstallInterruptFlag();

  ProgressBar bar("generate " + scenario.name);
  auto on_progress = [&](const sim::GenerationProgress& p) {
    if (!args.quiet) bar.Update(p.frames_done, p.frames_total, p.frames_per_second,
                                fmt::format("pass{}", p.pass_index + 1));
  };
  const sim::GenerateSummary summary = sim::GenerateDataset(scenario, args.out_dir, options, on_progress);
  bar.Finish();
  fmt::print("generated {} frames of '{}' into {} in {:.1f} s ({:.1f} frames/s, renderer {}, {})\n",
             summary.frames, scenario.name, args.out_dir, summary.seconds,
             summary.FramesPerSecond(), sim::GlBackendName(options.backend), summary.gl_renderer);
  if (summary.movers_left_out > 0) {
    fmt::print("note: {} of the scenario's moving cars and pedestrians were left out: no path tried kept them "
               "clear of the others (manifest.json: extra.movers_left_out)\n",
               summary.movers_left_out);
  }
  if (summary.red_lights_left_out > 0) {
    fmt::print("note: {} of the scenario's {} red lights were left out: the route has too few intersections, or "
               "they are too near the start or the light before to brake for at city.camera_speed_mps "
               "(manifest.json: extra.red_lights_left_out)\n",
               summary.red_lights_left_out, scenario.city.red_lights);
  }
  return 0;
}

}  // namespace

void AddGenerateCommand(CLI::App& app, std::function<int()>* action) {
  auto args = std::make_shared<GenerateArgs>();
  CLI::App* command = app.add_subcommand(
      "generate", "Render a scenario's two passes into a TUM-layout RGB-D dataset with masks");
  command->add_option("scenario", args->scenario_file, "Scenario YAML file")->required();
  command->add_option("--out,-o", args->out_dir, "Output directory (created; must not exist "
                                                 "unless --force)")->required();
  command->add_option("--gl", args->gl, "Off-screen GL back-end: osmesa or egl")
      ->capture_default_str();
  command->add_option("--frames", args->frames, "Render at most N frames per pass (0 = all)")
      ->check(CLI::NonNegativeNumber);
  command->add_option("--threads", args->threads,
                      "Threads for sensor noise and PNG encoding (0 = all cores)")
      ->check(CLI::NonNegativeNumber);
  command->add_option("--set", args->overrides,
                      "Override a scenario key, e.g. --set city.moving_cars=8 (repeatable)");
  command->add_flag("--force", args->force, "Replace an existing output directory");
  command->add_flag("--quiet,-q", args->quiet, "No progress bar");
  command->callback([args, action] { *action = [args] { return RunGenerate(*args); }; });
}

}  // namespace segslam::harness
