// The `segslam` command line: one executable, one subcommand per user task
// (generate, bench ...). Returns the process exit code; errors are one line on stderr.
#pragma once

namespace segslam::harness {

// The exit codes of every subcommand (also in `segslam --help` and docs/usage.md).
constexpr int kExitSuccess = 0;
// A bad command line or option, an input that cannot be read or is refused, a failed
// write: one line on stderr names the option or file and says what is wrong.
constexpr int kExitError = 1;
// scenario run, scenario suite: an expectation of the scenario failed.
constexpr int kExitExpectationFailed = 2;
// A bug in segslam (an exception it did not expect).
constexpr int kExitInternalError = 3;
// Interrupted (Ctrl-C, SIGTERM), 128 + SIGINT as shells report it.
constexpr int kExitInterrupted = 130;

int RunCli(int argc, char** argv);

}  // namespace segslam::harness
