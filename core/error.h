// The one exception type segslam throws for bad input and failed I/O. Messages name
// the file (and key or line) and say what is wrong, so the CLI can print them as is.
#pragma once

#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include "core/strings.h"  // PrintableText, which messages quote input with

namespace segslam {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "<file>: <what>"
inline Error FileError(const std::filesystem::path& file, const std::string& what) {
  return Error(file.string() + ": " + what);
}

}  // namespace segslam
