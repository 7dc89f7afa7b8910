#include "harness/dataset_cache.h"

#include <algorithm>
#include <cerrno>
#include <limits>
#include <regex>
#include <signal.h>
#include <sys/types.h>
#include <system_error>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_file.h"

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

fs::path RecordPath(const fs::path& dataset_dir) {
  fs::path dir = dataset_dir;
  if (dir.filename().empty()) dir = dir.parent_path();
  return dir.parent_path() / (dir.filename().string() + ".json");
}

bool HoldsSegslamManifest(const fs::path& dir) {
  try {
    const nlohmann::json manifest = ReadJsonFile(dir / "manifest.json");
    return manifest.is_object() && manifest.value("format", "").rfind("segslam-manifest", 0) == 0;
  } catch (const Error&) {
    return false;
  }
}

std::uintmax_t FolderBytes(const fs::path& dir) {
  std::uintmax_t bytes = 0;
  std::error_code error;
  for (fs::recursive_directory_iterator it(dir, error), end; !error && it != end; it.increment(error)) {
    std::error_code size_error;
    if (it->is_regular_file(size_error)) {
      const std::uintmax_t size = it->file_size(size_error);
      if (!size_error) bytes += size;
    }
  }
  return bytes;
}

// Signal 0 only asks whether the process exists; a number no pid can be names none.
bool ProcessIsGone(long long pid) {
  if (pid <= 0 || pid > std::numeric_limits<pid_t>::max()) return true;
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

}  // namespace

void RecordCachedDataset(const fs::path& dataset_dir, const std::string& scenario_name, int frames,
                         const std::string& code_version) {
  const nlohmann::json record = {
      {"code_version", code_version}, {"scenario", scenario_name}, {"frames_per_pass_limit", frames}};
  WriteFileAtomically(RecordPath(dataset_dir), record.dump(2) + "\n");
}

std::vector<CachedDataset> ListDatasetCache(const fs::path& cache_dir) {
  static const std::regex kDataset(R"(.+-[0-9a-f]{12})");
  static const std::regex kLeftover(R"(\..+-[0-9a-f]{12}\.(partial|old)-([0-9]{1,10}))");
  std::vector<CachedDataset> entries;
  std::error_code error;
  if (!fs::is_directory(cache_dir, error)) return entries;
  for (const fs::directory_entry& item : fs::directory_iterator(cache_dir, error)) {
    std::error_code type_error;
    if (!item.is_directory(type_error)) continue;
    const std::string name = item.path().filename().string();
    std::smatch match;
    CachedDataset entry;
    entry.dir = item.path();
    if (std::regex_match(name, match, kLeftover)) {
      if (!ProcessIsGone(std::stoll(match[2].str()))) continue;  // a generation still at work
      entry.leftover = true;
    } else if (std::regex_match(name, kDataset) && HoldsSegslamManifest(item.path())) {
      const fs::path record = RecordPath(item.path());
      if (fs::exists(record)) {
        try {
          entry.code_version = ReadJsonFile(record).value("code_version", "");
        } catch (const std::exception&) {
          // A record that cannot be read says nothing: the dataset counts as unrecorded.
        }
      }
    } else {
      continue;
    }
    entry.bytes = FolderBytes(item.path());
    entries.push_back(std::move(entry));
  }
  if (error) throw FileError(cache_dir, "cannot list: " + error.message());
  std::sort(entries.begin(), entries.end(),
            [](const CachedDataset& a, const CachedDataset& b) { return a.dir.filename() < b.dir.filename(); });
  return entries;
}

bool IsStale(const CachedDataset& entry, const std::string& current_code_version) {
  return entry.leftover || entry.code_version != current_code_version;
}

void RemoveCachedDataset(const CachedDataset& entry) {
  std::error_code error;
  fs::remove_all(entry.dir, error);
  if (error) throw FileError(entry.dir, "cannot remove: " + error.message());
  if (!entry.leftover) {
    fs::remove(RecordPath(entry.dir), error);
    if (error) throw FileError(RecordPath(entry.dir), "cannot remove: " + error.message());
  }
}

}  // namespace segslam::harness
