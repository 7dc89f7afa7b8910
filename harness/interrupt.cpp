#include "harness/interrupt.h"

#include <csignal>
#include <cstdlib>

namespace segslam::harness {
namespace {

std::atomic<bool> interrupt_requested{false};

extern "C" void OnInterrupt(int /*signal*/) {
  if (interrupt_requested.exchange(true)) std::_Exit(130);
}

}  // namespace

bool InterruptRequested() { return interrupt_requested.load(); }

const std::atomic<bool>* InstallInterruptFlag() {
  std::signal(SIGINT, OnInterrupt);
  std::signal(SIGTERM, OnInterrupt);
  return &interrupt_requested;
}

}  // namespace segslam::harness
