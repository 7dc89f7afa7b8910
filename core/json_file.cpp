#include "core/json_file.h"

#include "core/error.h"

#include <fstream>

namespace segslam {

nlohmann::json ReadJsonFile(const std::filesystem::path& path) {
  std::ifstream file(path);
  if (!file) {
    throw FileError(path, std::filesystem::exists(path) ? "cannot open file"
                                                        : "file does not exist");
  }
  try {
    return nlohmann::json::parse(file);
  } catch (const nlohmann::json::exception& e) {
    throw FileError(path, std::string("malformed JSON: ") + e.what());
  }
}

}  // namespace segslam
