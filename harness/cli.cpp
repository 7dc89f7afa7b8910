#include "harness/cli.h"

#include "core/error.h"
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
namespace {

// `message` as it may reach a terminal: printable ASCII and well-formed UTF-8 (a folder
// named in another script) as they are, every other byte (control bytes, C1 controls,
// broken UTF-8) as \xNN. Readers quote what they read with PrintableText; this catches
// file text that reaches a message unquoted (a path listed in a file, a name read from
// one), so that no file's bytes clear the screen or move the cursor (issue 44, item 16).
std::string TerminalSafe(std::string_view message) {
  static const char kHex[] = "0123456789abcdef";
  std::string safe;
  for (std::size_t i = 0; i < message.size();) {
    const auto byte = static_cast<unsigned char>(message[i]);
    std::size_t length = 0;  // of a printable character starting at i; 0: escape the byte
    if (byte >= 0x20 && byte < 0x7f) {
      length = 1;
    } else if (byte >= 0xc2 && byte <= 0xf4) {
      const std::size_t n = byte < 0xe0 ? 2 : byte < 0xf0 ? 3 : 4;
      char32_t code = byte & (0x7f >> n);
      bool well_formed = i + n <= message.size();
      for (std::size_t k = 1; well_formed && k < n; ++k) {
        const auto next = static_cast<unsigned char>(message[i + k]);
        well_formed = (next & 0xc0) == 0x80;
        code = (code << 6) | (next & 0x3f);
      }
      // Not C1 controls (U+0080 to U+009F), overlong forms, surrogates or beyond U+10FFFF.
      const char32_t lowest = n == 2 ? 0xa0 : n == 3 ? 0x800 : 0x10000;
      if (well_formed && code >= lowest && code <= 0x10ffff && !(code >= 0xd800 && code <= 0xdfff)) length = n;
    }
    if (length > 0) {
      safe.append(message.substr(i, length));
      i += length;
    } else {
      safe += {'\\', 'x', kHex[byte >> 4], kHex[byte & 0xf]};
      ++i;
    }
  }
  return safe;
}

}  // namespace

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
