// Opening the files segslam is given, with errors that name the path. A folder or a
// missing file where a file is expected is refused before anything is read: an
// std::ifstream opens a folder and fails only at its first read, with a message that
// names neither the path nor the cause.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace segslam {

// Throws segslam::Error "<path>: file does not exist" or "<path>: is a directory, expected
// a file". A pipe passes (`<(command)` in a shell).
void CheckInputFile(const std::filesystem::path& path);

// CheckInputFile, then the open stream; "<path>: cannot open file: <reason>" when it
// cannot be opened.
std::ifstream OpenInputFile(const std::filesystem::path& path,
                            std::ios::openmode mode = std::ios::in);

// The whole file's bytes; the errors of OpenInputFile, and "<path>: read error".
std::string ReadFileText(const std::filesystem::path& path);

}  // namespace segslam
