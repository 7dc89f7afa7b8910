// Runs the segslam binary (SEGSLAM_BINARY) for CLI tests and captures what it prints.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>

#include <gtest/gtest.h>

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

// A test with its own scratch folder (removed afterwards) in which it runs the binary.
class CliScratchTest : public ::testing::Test {
 protected:
  explicit CliScratchTest(std::string prefix) : prefix_(std::move(prefix)) {}
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           (prefix_ + std::to_string(::getpid()) + "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  CommandOutput Run(const std::string& arguments) { return RunSegslam(arguments, dir_); }
  std::filesystem::path dir_;

 private:
  std::string prefix_;
};

}  // namespace segslam::testing
