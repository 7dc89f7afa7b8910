// The one exception type segslam throws for bad input and failed I/O. Messages name
// the file (and key or line) and say what is wrong, so the CLI can print them as is.
#pragma once

#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace segslam {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "<file>: <what>"
inline Error FileError(const std::filesystem::path& file, const std::string& what) {
  return Error(file.string() + ": " + what);
}

// `text` (read from a file) as a message may quote it: printable ASCII as is, every other
// byte as \xNN, so that a binary file's bytes cannot garble the terminal; cut after
// `max_chars` bytes of `text` with "...".
inline std::string PrintableText(std::string_view text, std::size_t max_chars = 60) {
  static const char kHex[] = "0123456789abcdef";
  std::string printable;
  for (std::size_t i = 0; i < text.size() && i < max_chars; ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if (byte >= 0x20 && byte < 0x7f) {
      printable += static_cast<char>(byte);
    } else {
      printable += {'\\', 'x', kHex[byte >> 4], kHex[byte & 0xf]};
    }
  }
  if (text.size() > max_chars) printable += "...";
  return printable;
}

}  // namespace segslam
