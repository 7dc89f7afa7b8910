#include "harness/cli.h"

#include "core/error.h"
#include "harness/commands.h"
#include "harness/interrupt.h"
#include "segslam_version.h"  // generated at build time: SEGSLAM_VERSION

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>

namespace segslam::harness {

int RunCli(int argc, char** argv) {
  CLI::App app{
      "segslam: a headless simulation-in-the-loop test bench for RGB-D SLAM among moving and "
      "relocated objects"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("segslam ") + SEGSLAM_VERSION);

  // Each subcommand registers its options and the action to run once parsing succeeded.
  std::function<int()> action;
  AddGenerateCommand(app, &action);
  AddBenchCommand(app, &action);
  AddPreviewCommand(app, &action);
  AddSegEvalCommand(app, &action);
  AddEvalTrajCommand(app, &action);
  AddRunCommand(app, &action);
  AddEvalCommand(app, &action);
  AddScenarioCommand(app, &action);
  AddSweepCommand(app, &action);
  AddMasksCommand(app, &action);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    return action ? action() : 0;
  } catch (const Error& e) {
    std::fprintf(stderr, "segslam: error: %s\n", e.what());
    return InterruptRequested() ? 130 : 1;
  } catch (const std::filesystem::filesystem_error& e) {
    // A folder that cannot be made or read: the user's to fix, not an internal error.
    std::fprintf(stderr, "segslam: error: %s\n", e.what());
    return InterruptRequested() ? 130 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "segslam: internal error: %s\n", e.what());
    return 3;
  }
}

}  // namespace segslam::harness
