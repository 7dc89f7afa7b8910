#include "core/output_folders.h"

#include <fstream>
#include <set>
#include <string>
#include <system_error>

#include <nlohmann/json.hpp>

namespace segslam {
namespace {

namespace fs = std::filesystem;

// A JSON object's string value, "" when the file is unreadable, not JSON or lacks it.
std::string JsonStringField(const fs::path& file, const char* key) {
  std::ifstream in(file);
  if (!in) return "";
  const nlohmann::json json = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!json.is_object() || !json.contains(key) || !json.at(key).is_string()) return "";
  return json.at(key).get<std::string>();
}

bool StartsWith(const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; }

// Runs of builds before run.json are known by their trajectory's first line.
bool HasSegslamRunTrajectory(const fs::path& dir) {
  std::ifstream in(dir / "trajectory.txt");
  std::string first_line;
  return in && std::getline(in, first_line) && StartsWith(first_line, "# segslam run");
}

bool IsFileOfKind(const fs::directory_entry& entry, std::initializer_list<const char*> extensions) {
  std::error_code error;
  if (!entry.is_regular_file(error)) return false;
  const std::string extension = entry.path().extension().string();
  for (const char* allowed : extensions) {
    if (extension == allowed) return true;
  }
  return false;
}

// The first entry of a run's folder (or of one of its passes) that a run does not write.
std::string ForeignEntryOfRunFolder(const fs::path& dir, const fs::path& shown_as, bool top_level) {
  static const std::set<std::string> kRunFiles = {"trajectory.txt", "frames.jsonl", "seg.json"};
  std::error_code error;
  for (fs::directory_iterator it(dir, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    const fs::path shown = shown_as / name;
    std::error_code type_error;
    if (it->is_directory(type_error) && !it->is_symlink(type_error)) {
      if (name == "refined_masks") {
        for (fs::directory_iterator mask(it->path(), error), mask_end; !error && mask != mask_end;
             mask.increment(error)) {
          if (!IsFileOfKind(*mask, {".png", ".json"})) {
            return (shown / mask->path().filename()).generic_string() + " is no file of a run";
          }
        }
        continue;
      }
      if (top_level && (name == "pass1" || name == "pass2")) {
        const std::string foreign = ForeignEntryOfRunFolder(it->path(), shown, /*top_level=*/false);
        if (!foreign.empty()) return foreign;
        continue;
      }
      return shown.generic_string() + "/ is no folder of a run";
    }
    const bool run_file = kRunFiles.count(name) > 0 || (top_level && name == kRunRecordFile) ||
                          IsFileOfKind(*it, {".segslam", ".ply"});
    if (!run_file || !it->is_regular_file(type_error)) return shown.generic_string() + " is no file of a run";
  }
  if (error) return "cannot list " + dir.string() + ": " + error.message();
  return "";
}

bool IsOwnFolderInsideDataset(const fs::path& dir) {
  return ForeignContentOfRunOutput(dir).empty() || ForeignContentOfMaskFolder(dir).empty();
}

}  // namespace

bool HoldsSegslamManifest(const fs::path& dir) {
  return StartsWith(JsonStringField(dir / kManifestFile, "format"), "segslam-manifest");
}

std::string ForeignContentOfDataset(const fs::path& dir) {
  if (!HoldsSegslamManifest(dir)) return std::string("no segslam ") + kManifestFile;
  std::set<std::string> listed;
  {
    std::ifstream in(dir / kManifestFile);
    const nlohmann::json manifest = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
    const auto files = manifest.find("files");
    if (files == manifest.end() || !files->is_array()) return std::string("a ") + kManifestFile + " without files";
    for (const nlohmann::json& file : *files) {
      if (file.is_object() && file.contains("path") && file.at("path").is_string()) {
        listed.insert(file.at("path").get<std::string>());
      }
    }
  }
  std::error_code error;
  for (fs::recursive_directory_iterator it(dir, error), end; !error && it != end; it.increment(error)) {
    std::error_code type_error;
    if (it->is_directory(type_error) && !it->is_symlink(type_error)) {
      // A run or mask folder segslam wrote inside the dataset (`run`'s default output is
      // DATASET/run_MODE) goes with it; folders themselves hold nothing to lose.
      if (IsOwnFolderInsideDataset(it->path())) it.disable_recursion_pending();
      continue;
    }
    const std::string relative = fs::relative(it->path(), dir).generic_string();
    if (relative == kManifestFile) continue;
    if (!listed.count(relative)) return relative + " is in no " + kManifestFile;
  }
  if (error) return "cannot list it: " + error.message();
  return "";
}

std::string ForeignContentOfRunOutput(const fs::path& dir) {
  const bool recorded = StartsWith(JsonStringField(dir / kRunRecordFile, "format"), "segslam-run");
  if (!recorded && !HasSegslamRunTrajectory(dir) && !HasSegslamRunTrajectory(dir / "pass1")) {
    return std::string("no ") + kRunRecordFile + " of segslam run";
  }
  return ForeignEntryOfRunFolder(dir, "", /*top_level=*/true);
}

std::string ForeignContentOfMaskFolder(const fs::path& dir) {
  if (!fs::is_regular_file(dir / kMaskFolderRecordFile)) return std::string("no ") + kMaskFolderRecordFile;
  std::error_code error;
  for (fs::directory_iterator it(dir, error), end; !error && it != end; it.increment(error)) {
    if (!IsFileOfKind(*it, {".png", ".json"})) {
      return it->path().filename().string() + " is no file of a mask folder";
    }
  }
  if (error) return "cannot list it: " + error.message();
  return "";
}

}  // namespace segslam
