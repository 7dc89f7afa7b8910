// `segslam generate SCENARIO --out DIR`: renders the scenario's two passes into a dataset,
// and records their aliasing measure (harness/aliasing_report.h) in its manifest.json.
#include "core/error.h"
#include "harness/aliasing_report.h"
#include "harness/cli_numbers.h"
#include "harness/commands.h"
#include "harness/interrupt.h"
#include "harness/progress_bar.h"
#include "scenes/scenario.h"
#include "sim/dataset_generator.h"

#include <fmt/format.h>

#include <chrono>
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
  bool no_aliasing = false;
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
  // The aliasing measure of both passes, in the staging folder before it is renamed into
  // place, so the manifest that says the dataset is complete carries it too.
  std::vector<std::pair<std::string, AliasingSummary>> aliasing;
  double aliasing_seconds = 0;
  if (!args.no_aliasing) {
    options.staged_extra = [&](const std::filesystem::path& staged_dir) {
      bar.Finish();
      const auto start = std::chrono::steady_clock::now();
      AliasingOptions aliasing_options = ManifestAliasingOptions();
      aliasing_options.threads = args.threads;
      aliasing_options.cancel = options.cancel;
      aliasing = MeasureAliasingOfFolder(aliasing_options, staged_dir, "", !args.quiet);
      aliasing_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      return nlohmann::json{{"aliasing", ManifestAliasingSummary(aliasing_options, aliasing)}};
    };
  }
  const sim::GenerateSummary summary = sim::GenerateDataset(scenario, args.out_dir, options, on_progress);
  bar.Finish();
  fmt::print("generated {} frames of '{}' into {} in {:.1f} s ({:.1f} frames/s, renderer {}, {})\n",
             summary.frames, scenario.name, args.out_dir, summary.seconds,
             summary.FramesPerSecond(), sim::GlBackendName(options.backend), summary.gl_renderer);
  if (!aliasing.empty()) {
    std::string figures;
    for (const auto& [name, pass] : aliasing) {
      figures += fmt::format("{}{} {} verified matches at most, {} pairs >= {}", figures.empty() ? "" : "; ", name,
                             pass.max_verified_matches, pass.pairs_at_or_above_acceptance, kLoopAcceptanceMatches);
    }
    fmt::print("aliasing between views with nothing in common (manifest.json: extra.aliasing; segslam bench aliasing "
               "for the detail): {}; measured in {:.1f} s, {:.0f} % of the generation\n",
               figures, aliasing_seconds, summary.seconds > 0 ? 100.0 * aliasing_seconds / summary.seconds : 0.0);
  }
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
      ->check(WholeNumberIn(0, kMaxFrames, "0 = all"));
  command->add_option("--threads", args->threads,
                      "Threads for sensor noise and PNG encoding (0 = all cores)")
      ->check(WholeNumberIn(0, kMaxThreads, "0 = all cores"));
  command->add_option("--set", args->overrides,
                      "Override a scenario key, e.g. --set city.moving_cars=8 (repeatable)");
  command->add_flag("--force", args->force, "Replace an existing output directory");
  command->add_flag("--quiet,-q", args->quiet, "No progress bar");
  command->add_flag("--no-aliasing", args->no_aliasing,
                    "Do not measure the passes' aliasing for manifest.json (saves about a tenth of the time)");
  command->callback([args, action] { *action = [args] { return RunGenerate(*args); }; });
}

}  // namespace segslam::harness
