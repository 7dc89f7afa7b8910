// The datasets `scenario run` generates once and reuses (sweeps and suites go through it):
// CACHE/<scenario name>-<key>/, the key a hash of the effective scenario, the frame limit
// and the code version. Each new build therefore generates anew and leaves the old
// datasets behind (a city route is about 0.9 GB), so every dataset has a record beside
// it, CACHE/<name>-<key>.json, naming the build that generated it, and `segslam scenario
// prune-cache` removes the datasets this build can no longer reach.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace segslam::harness {

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
