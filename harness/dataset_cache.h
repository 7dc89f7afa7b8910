// The datasets `scenario run` generates once and reuses (sweeps and suites go through it):
// CACHE/<scenario name>-<key>/, the key a hash of the effective scenario, the frame limit
// and the code version. Each new build therefore generates anew and leaves the old
// datasets behind (a city route is about 0.9 GB), so every dataset has a record beside
// it, CACHE/<name>-<key>.json, naming the build that generated it, and `segslam scenario
// prune-cache` removes the datasets this build can no longer reach.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "scenes/scenario.h"
#include "sim/dataset_generator.h"

namespace segslam::harness {

// The key of a scenario's dataset: a hash of the world description (not of `expect:` or
// `bench:`), the frame limit and the generator's code, 12 hex digits.
std::string DatasetCacheKey(const scenes::Scenario& scenario, int frames, sim::GlBackend backend);

// The lock a process that generates `dataset_dir` holds (core/owner_lock.h): a hidden file
// beside it, ".<name>.lock".
std::filesystem::path DatasetLockPath(const std::filesystem::path& dataset_dir);

// How GenerateUnlessAnotherProcessDoes came by the dataset.
enum class DatasetOrigin { kGenerated, kMadeByAnotherProcess };

// Calls `generate` to make `dataset_dir` while holding its lock, unless another process
// (on this host, or on another over a shared file system) holds it: then waits, printing
// who it waits for, and returns kMadeByAnotherProcess as soon as `made_by_another()`
// says the dataset is there (it is asked before each try, and once more after the lock
// is taken). `key` says what is generated (DatasetCacheKey): with `refuse_other_key`, a
// holder generating something else into the same folder is an error naming it rather
// than waited for. The lock of an owner that died is broken (owner_lock.h).
DatasetOrigin GenerateUnlessAnotherProcessDoes(const std::filesystem::path& dataset_dir, const std::string& key,
                                               bool refuse_other_key, const std::function<bool()>& made_by_another,
                                               const std::function<void()>& generate,
                                               const std::atomic<bool>* cancel);

struct CachedDataset {
  std::filesystem::path dir;
  std::string code_version;  // of the build that generated it; empty: no record
  std::uintmax_t bytes = 0;
  // A staging folder (.<name>-<key>.partial-<pid>@<host>, .old-<pid>@<host>) whose
  // process on this host is gone: what a generation killed half-way leaves. One of
  // another host (a cache on a shared file system) is not listed.
  bool leftover = false;
};

// A cached dataset checked against its manifest.json before it is reused.
struct CachedDatasetCheck {
  std::vector<std::string> problems;  // one per file (core/manifest.h: CheckListedFiles); empty: intact
  bool hashed = false;                // SHA-256s were compared, not only sizes
  double seconds = 0;
};

// Every file the manifest lists must be there with its size, each time (a stat per file);
// its SHA-256 is compared too the first time this process checks the dataset, or every
// time with `always_hash` (an edited PNG may keep its size).
CachedDatasetCheck CheckCachedDataset(const std::filesystem::path& dataset_dir, bool always_hash = false);

// Writes the record of `dataset_dir` (atomically), e.g. after generating it.
void RecordCachedDataset(const std::filesystem::path& dataset_dir, const std::string& scenario_name, int frames,
                         const std::string& code_version);

// The cache's datasets and leftovers, by name. Only folders named <name>-<12 hex digits>
// that hold a segslam manifest count as datasets, so a cache folder given by mistake
// (a home directory) lists nothing of its other contents. A missing folder lists nothing.
std::vector<CachedDataset> ListDatasetCache(const std::filesystem::path& cache_dir);

// What prune removes: leftovers, and datasets of another build or without a record
// (made before records were kept, or by hand).
bool IsStale(const CachedDataset& entry, const std::string& current_code_version);

// Removes the dataset (or leftover) and its record. Throws segslam::Error naming the
// folder when it cannot.
void RemoveCachedDataset(const CachedDataset& entry);

}  // namespace segslam::harness
