#include "tests/fuzz/fuzz_util.h"

#include <fstream>
#include <system_error>

#include <unistd.h>

namespace segslam::fuzz {

namespace fs = std::filesystem;

namespace {

void RemoveScratchDir() {
  std::error_code ignored;
  fs::remove_all(ScratchDir(), ignored);
}

}  // namespace

const fs::path& ScratchDir() {
  // Never destroyed, so that it outlives the exit handler that removes the folder.
  static const fs::path* const dir = [] {
    auto* d = new fs::path(fs::temp_directory_path() / ("segslam-fuzz-" + std::to_string(::getpid())));
    fs::create_directories(*d);
    std::atexit(RemoveScratchDir);
    return d;
  }();
  return *dir;
}

fs::path WriteScratch(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const fs::path path = ScratchDir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) {
    std::fprintf(stderr, "fuzz harness: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path;
}

fs::path WriteScratch(const std::string& name, const std::string& text) {
  return WriteScratch(name, reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

}  // namespace segslam::fuzz
