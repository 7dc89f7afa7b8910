// Dataset manifests: every file of a dataset directory with its size and SHA-256, so a
// consumer can tell a complete, unmodified dataset from a partial or edited one.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace segslam {

struct ManifestEntry {
  std::string path;  // relative to the manifest's directory, '/'-separated
  std::uintmax_t size_bytes = 0;
  std::string sha256;  // lowercase hex
};

// SHA-256 of a file's bytes, lowercase hex. Throws segslam::Error if unreadable.
std::string Sha256OfFile(const std::filesystem::path& file);

// Every regular file under `dir`, recursively, sorted by path, excluding `exclude`
// (relative names, e.g. the manifest itself).
std::vector<ManifestEntry> ListDirectoryWithChecksums(const std::filesystem::path& dir,
                                                      const std::vector<std::string>& exclude);

// Writes `dir/manifest.json` atomically: {"format": ..., "extra": ..., "files": [...]}.
void WriteManifest(const std::filesystem::path& dir, const nlohmann::json& extra);

// Recomputes every checksum listed in dir/manifest.json. Returns the problems found
// (missing file, size or checksum mismatch, unlisted file); empty means intact.
std::vector<std::string> VerifyManifest(const std::filesystem::path& dir);

// Checks the files that dir/manifest.json lists: each present with its listed size and,
// with `hashes`, its SHA-256. Files it does not list are not looked at (a run's output
// may lie inside a dataset). Returns the problems, one per file, e.g.
// "pass1/depth/0.033333.png: missing"; empty means intact. Sizes cost a stat per file;
// hashes read every byte.
std::vector<std::string> CheckListedFiles(const std::filesystem::path& dir, bool hashes);

}  // namespace segslam
