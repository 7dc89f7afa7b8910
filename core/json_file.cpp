#include "core/json_file.h"

#include "core/error.h"
#include "core/input_file.h"

namespace segslam {

nlohmann::json ReadJsonFile(const std::filesystem::path& path) {
  std::ifstream file = OpenInputFile(path);
  try {
    return nlohmann::json::parse(file);
  } catch (const nlohmann::json::exception& e) {
    throw FileError(path, std::string("malformed JSON: ") + e.what());
  }
}

}  // namespace segslam
