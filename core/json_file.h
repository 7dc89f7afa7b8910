// Reading JSON files with errors that name the file: missing, unreadable, malformed.
#pragma once

#include <filesystem>

#include <nlohmann/json.hpp>

namespace segslam {

// Parses `path`; throws segslam::Error with OpenInputFile's messages (core/input_file.h:
// "<path>: file does not exist", "is a directory, expected a file", ...) or "<path>:
// malformed JSON: ...".
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

}  // namespace segslam
