#include "harness/cli.h"

#include "core/error.h"
#include "core/strings.h"
#include "harness/commands.h"
#include "harness/interrupt.h"
#include "segslam_version.h"  // generated at build time: SEGSLAM_VERSION

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace segslam::harness {

int RunCli(int argc, char** argv) {
  CLI::App app{
      "segslam: a headless simulation-in-the-loop test bench for RGB-D SLAM among moving and "
      "relocated objects"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("segslam ") + SEGSLAM_VERSION);
  // Before the subcommands are added: each copies its parent's footer.
  app.footer(
      "Exit codes: 0 done; 1 an error (a bad command line, an input refused or unreadable, a failed write: one line "
      "on stderr says what and where); 2 an expectation failed (scenario run, scenario suite); 3 an internal error "
      "(a bug in segslam); 130 interrupted.");
  // Usage errors as every other error: one line naming the option, exit code 1 (CLI11's
  // own codes, 101 to 115, would say nothing the message does not).
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return "segslam: error: " + TerminalSafe(e.what()) + " (--help lists the options)\n";
  });

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
  AddOptionsCommand(app, &action);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Prints help or the version (code 0), or the failure message.
    return app.exit(e) == 0 ? kExitSuccess : kExitError;
  }
  try {
    return action ? action() : 0;
  } catch (const Error& e) {
    std::fprintf(stderr, "segslam: error: %s\n", TerminalSafe(e.what()).c_str());
    return InterruptRequested() ? kExitInterrupted : kExitError;
  } catch (const std::filesystem::filesystem_error& e) {
    // A folder that cannot be made or read: the user's to fix, not an internal error.
    std::fprintf(stderr, "segslam: error: %s\n", TerminalSafe(e.what()).c_str());
    return InterruptRequested() ? kExitInterrupted : kExitError;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "segslam: internal error: %s\n", TerminalSafe(e.what()).c_str());
    return kExitInternalError;
  }
}

}  // namespace segslam::harness
