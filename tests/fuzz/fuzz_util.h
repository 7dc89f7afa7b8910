// Shared by the fuzz targets (tests/fuzz/): scratch files for readers that take a path,
// and the rule every target follows: a segslam::Error is a clean refusal; anything else
// that leaves a reader (another exception type, a crash, a sanitizer report) is a bug and
// reaches libFuzzer, which fails the run.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/error.h"

namespace segslam::fuzz {

// A folder of this process's own under the system's temporary folder, created on first
// use and removed when the process exits normally.
const std::filesystem::path& ScratchDir();

// Writes `size` bytes to ScratchDir()/name (replacing it) and returns its path.
std::filesystem::path WriteScratch(const std::string& name, const std::uint8_t* data, std::size_t size);
std::filesystem::path WriteScratch(const std::string& name, const std::string& text);

// Runs `read`; a segslam::Error is a clean refusal and returns false. Every other
// exception propagates (libFuzzer reports it as a crash with the input).
template <class Read>
bool Refused(Read&& read) {
  try {
    read();
    return false;
  } catch (const segslam::Error&) {
    return true;
  }
}

// For a property that must hold of every input a reader accepted (e.g. a round trip):
// prints `what` and aborts, so that libFuzzer keeps the input.
[[noreturn]] inline void PropertyBroken(const std::string& what) {
  std::fprintf(stderr, "fuzz property broken: %s\n", what.c_str());
  std::abort();
}

}  // namespace segslam::fuzz
