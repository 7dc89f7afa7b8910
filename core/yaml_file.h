// Reading YAML with errors that name the file and line: missing, a folder, malformed, or
// holding one key twice in a mapping. yaml-cpp accepts a repeated key, keeps both, and a
// lookup quietly takes the first: a user who overrides a value further down a file would
// see their edit ignored.
#pragma once

#include <filesystem>
#include <string>

#include <yaml-cpp/yaml.h>

namespace segslam {

// Throws segslam::Error "<origin>: line N: key 'K' appears twice in one mapping (first on
// line M)" for the first such key, searched through every nested mapping and list.
void CheckNoDuplicateKeys(const YAML::Node& node, const std::string& origin);

// Parses `text`; throws segslam::Error "<origin>: line N: malformed YAML: <yaml-cpp's
// message>" on a syntax error and refuses repeated keys (CheckNoDuplicateKeys).
YAML::Node LoadYamlText(const std::string& text, const std::string& origin);

// LoadYamlText of the file's bytes, with the errors of ReadFileText (core/input_file.h).
YAML::Node LoadYamlFile(const std::filesystem::path& path);

}  // namespace segslam
