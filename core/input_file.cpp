#include "core/input_file.h"

#include <cerrno>
#include <cstring>
#include <sstream>

#include "core/error.h"

namespace segslam {

void CheckInputFile(const std::filesystem::path& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) throw FileError(path, "file does not exist");
  if (status.type() == std::filesystem::file_type::directory) {
    throw FileError(path, "is a directory, expected a file");
  }
}

std::ifstream OpenInputFile(const std::filesystem::path& path, std::ios::openmode mode) {
  CheckInputFile(path);
  errno = 0;
  std::ifstream file(path, mode);
  if (!file) {
    throw FileError(path, std::string("cannot open file") + (errno != 0 ? ": " + std::string(std::strerror(errno)) : ""));
  }
  return file;
}

std::string ReadFileText(const std::filesystem::path& path) {
  std::ifstream file = OpenInputFile(path, std::ios::in | std::ios::binary);
  std::ostringstream bytes;
  bytes << file.rdbuf();
  if (file.bad()) throw FileError(path, "read error");
  return bytes.str();
}

}  // namespace segslam
