// Reading JSON files with errors that name the file: missing, unreadable, malformed.
#pragma once

#include <filesystem>

#include <nlohmann/json.hpp>

namespace segslam {

// Parses `path`; throws segslam::Error "<path>: file does not exist" / "cannot open
// file" / "malformed JSON: ...".
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

}  // namespace segslam
