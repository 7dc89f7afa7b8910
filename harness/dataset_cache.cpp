#include "harness/dataset_cache.h"

#include <algorithm>
#include <chrono>
#include <mutex>
#include <optional>
#include <regex>
#include <set>
#include <system_error>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_file.h"
#include "core/manifest.h"
#include "core/output_folders.h"

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

fs::path RecordPath(const fs::path& dataset_dir) {
  fs::path dir = dataset_dir;
  if (dir.filename().empty()) dir = dir.parent_path();
  return dir.parent_path() / (dir.filename().string() + ".json");
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

}  // namespace

void RecordCachedDataset(const fs::path& dataset_dir, const std::string& scenario_name, int frames,
                         const std::string& code_version) {
  const nlohmann::json record = {
      {"code_version", code_version}, {"scenario", scenario_name}, {"frames_per_pass_limit", frames}};
  WriteFileAtomically(RecordPath(dataset_dir), record.dump(2) + "\n");
}

CachedDatasetCheck CheckCachedDataset(const fs::path& dataset_dir, bool always_hash) {
  // Datasets this process has hashed (several scenarios of a suite may share one).
  static std::mutex hashed_mutex;
  static std::set<std::string> hashed;
  const std::string key = fs::weakly_canonical(dataset_dir).string();
  CachedDatasetCheck check;
  {
    std::lock_guard<std::mutex> lock(hashed_mutex);
    check.hashed = always_hash || hashed.count(key) == 0;
  }
  const auto start = std::chrono::steady_clock::now();
  check.problems = CheckListedFiles(dataset_dir, check.hashed);
  check.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (check.hashed && check.problems.empty()) {
    std::lock_guard<std::mutex> lock(hashed_mutex);
    hashed.insert(key);
  }
  return check;
}

std::vector<CachedDataset> ListDatasetCache(const fs::path& cache_dir) {
  static const std::regex kDataset(R"(.+-[0-9a-f]{12})");
  std::vector<CachedDataset> entries;
  std::error_code error;
  if (!fs::is_directory(cache_dir, error)) return entries;
  for (const fs::directory_entry& item : fs::directory_iterator(cache_dir, error)) {
    std::error_code type_error;
    if (!item.is_directory(type_error)) continue;
    const std::string name = item.path().filename().string();
    CachedDataset entry;
    entry.dir = item.path();
    if (const std::optional<StagingLeftover> leftover = ParseStagingLeftover(item.path());
        leftover && std::regex_match(leftover->target_name, kDataset)) {
      // A generation still at work, or one of another host sharing the folder, is left be.
      if (!IsAbandoned(*leftover)) continue;
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
