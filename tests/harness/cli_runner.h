// Runs the segslam binary (SEGSLAM_BINARY) for CLI tests and captures what it prints.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace segslam::testing {

struct CommandOutput {
  int exit_code = -1;
  std::string stdout_text, stderr_text;
};

inline std::string ReadText(const std::filesystem::path& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// `arguments` are shell-quoted by the caller; `scratch_dir` holds the captured streams.
inline CommandOutput RunSegslam(const std::string& arguments, const std::filesystem::path& scratch_dir) {
  const std::filesystem::path out = scratch_dir / "stdout.txt", err = scratch_dir / "stderr.txt";
  const std::string command = std::string(SEGSLAM_BINARY) + " " + arguments + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(command.c_str());
  CommandOutput result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.stdout_text = ReadText(out);
  result.stderr_text = ReadText(err);
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return result;
}

inline int LineCount(const std::string& text) {
  int lines = 0;
  for (const char c : text) lines += c == '\n';
  return lines;
}

}  // namespace segslam::testing
