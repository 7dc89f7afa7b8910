// Ctrl-C handling for long commands: the first SIGINT/SIGTERM asks the running job to
// stop at its next checkpoint (it then cleans up its partial output); a second one
// ends the process at once.
#pragma once

#include <atomic>

namespace segslam::harness {

// Installs the handlers and returns the flag they set.
const std::atomic<bool>* InstallInterruptFlag();

// Whether a SIGINT/SIGTERM arrived (the CLI then exits with 130, as shells expect).
bool InterruptRequested();

}  // namespace segslam::harness
