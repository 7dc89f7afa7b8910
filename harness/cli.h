// The `segslam` command line: one executable, one subcommand per user task
// (generate, bench ...). Returns the process exit code; errors are one line on stderr.
#pragma once

namespace segslam::harness {

int RunCli(int argc, char** argv);

}  // namespace segslam::harness
