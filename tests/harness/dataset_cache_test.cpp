// The dataset cache's records and pruning (harness/dataset_cache.h) on a hand-made cache
// folder: what counts as a dataset, which are stale, and that nothing else is touched.
#include "harness/dataset_cache.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/manifest.h"
#include "tests/core/test_util.h"

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

class DatasetCacheTest : public segslam::testing::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    cache_ = dir();
  }

  // A folder with a segslam manifest and one frame's worth of bytes.
  fs::path MakeDataset(const std::string& name) {
    const fs::path folder = cache_ / name;
    fs::create_directories(folder / "pass1");
    std::ofstream(folder / "manifest.json") << R"({"format": "segslam-manifest-1", "files": []})";
    std::ofstream(folder / "pass1" / "frame.png") << std::string(1000, 'x');
    return folder;
  }

  fs::path cache_;
};

TEST_F(DatasetCacheTest, ListsDatasetsAndLeftoversOnlyAndTellsWhichAreStale) {
  RecordCachedDataset(MakeDataset("office-0123456789ab"), "office", 0, "v2");
  RecordCachedDataset(MakeDataset("office-aaaaaaaaaaaa"), "office", 25, "v1");
  MakeDataset("city-bbbbbbbbbbbb");                                   // no record
  MakeDataset(".city-cccccccccccc.partial-2147483000");              // its process is gone
  MakeDataset(".city-dddddddddddd.partial-" + std::to_string(::getpid()));  // still at work
  MakeDataset("photos");                                              // not a cache name
  fs::create_directories(cache_ / "notes-eeeeeeeeeeee");              // no manifest
  std::ofstream(cache_ / "file-ffffffffffff") << "not a folder";

  const std::vector<CachedDataset> entries = ListDatasetCache(cache_);
  ASSERT_EQ(entries.size(), 4u);
  EXPECT_EQ(entries[0].dir.filename(), ".city-cccccccccccc.partial-2147483000");
  EXPECT_TRUE(entries[0].leftover);
  EXPECT_EQ(entries[1].dir.filename(), "city-bbbbbbbbbbbb");
  EXPECT_EQ(entries[1].code_version, "");
  EXPECT_EQ(entries[2].dir.filename(), "office-0123456789ab");
  EXPECT_EQ(entries[2].code_version, "v2");
  EXPECT_EQ(entries[3].code_version, "v1");
  for (const CachedDataset& entry : entries) EXPECT_GE(entry.bytes, 1000u) << entry.dir;

  EXPECT_TRUE(IsStale(entries[0], "v2"));
  EXPECT_TRUE(IsStale(entries[1], "v2"));
  EXPECT_FALSE(IsStale(entries[2], "v2"));
  EXPECT_TRUE(IsStale(entries[3], "v2"));
  EXPECT_FALSE(IsStale(entries[3], "v1"));

  const nlohmann::json record = nlohmann::json::parse(std::ifstream(cache_ / "office-aaaaaaaaaaaa.json"));
  EXPECT_EQ(record["scenario"], "office");
  EXPECT_EQ(record["frames_per_pass_limit"], 25);
}

TEST_F(DatasetCacheTest, RemovingADatasetTakesItsRecordAndNothingElse) {
  const fs::path old = MakeDataset("office-aaaaaaaaaaaa");
  RecordCachedDataset(old, "office", 0, "v1");
  const fs::path current = MakeDataset("office-0123456789ab");
  RecordCachedDataset(current, "office", 0, "v2");
  for (const CachedDataset& entry : ListDatasetCache(cache_)) {
    if (IsStale(entry, "v2")) RemoveCachedDataset(entry);
  }
  EXPECT_FALSE(fs::exists(old));
  EXPECT_FALSE(fs::exists(cache_ / "office-aaaaaaaaaaaa.json"));
  EXPECT_TRUE(fs::exists(current / "pass1" / "frame.png"));
  EXPECT_TRUE(fs::exists(cache_ / "office-0123456789ab.json"));
}

TEST_F(DatasetCacheTest, AMissingCacheListsNothingAndAnUnreadableRecordCountsAsNone) {
  EXPECT_TRUE(ListDatasetCache(cache_ / "missing").empty());
  MakeDataset("office-0123456789ab");
  std::ofstream(cache_ / "office-0123456789ab.json") << "{ not json";
  const std::vector<CachedDataset> entries = ListDatasetCache(cache_);
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_EQ(entries[0].code_version, "");
  EXPECT_TRUE(IsStale(entries[0], "v2"));
}

// A generation killed in the cache leaves .<name>-<key>.partial-<pid>@<host>: prune-cache
// lists it once its process on this host has ended; one of another host sharing the
// cache, or of a process still at work, is left alone.
TEST_F(DatasetCacheTest, LeftoversOfEndedProcessesOfThisHostOnlyAreListed) {
  const std::string host = StagingHostName();
  const std::string dead_pid = "2147483000";  // above any pid_max: no process has it
  MakeDataset(".office-0123456789ab.partial-" + dead_pid + "@" + host);
  MakeDataset(".office-0123456789ab.partial-" + dead_pid + "@not-" + host);
  MakeDataset(".office-0123456789ab.partial-" + std::to_string(::getpid()) + "@" + host);
  const std::vector<CachedDataset> entries = ListDatasetCache(cache_);
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_EQ(entries[0].dir.filename(), ".office-0123456789ab.partial-" + dead_pid + "@" + host);
  EXPECT_TRUE(entries[0].leftover);
}

// A cached dataset is checked against its manifest.json before reuse: sizes every time,
// SHA-256s on this process's first check of it (or always when asked), so a PNG edited in
// place (same size) is caught where a size check alone would miss it.
TEST_F(DatasetCacheTest, CachedDatasetIsCheckedAgainstItsManifest) {
  const fs::path dataset = cache_ / "office-cafecafecafe";
  fs::create_directories(dataset / "pass1" / "depth");
  std::ofstream(dataset / "pass1" / "depth" / "0.000000.png") << std::string(500, 'd');
  std::ofstream(dataset / "pass1" / "rgb.txt") << "0.000000 rgb/0.000000.png\n";
  WriteManifest(dataset, nlohmann::json::object());

  const CachedDatasetCheck first = CheckCachedDataset(dataset);
  EXPECT_TRUE(first.hashed);
  EXPECT_TRUE(first.problems.empty());

  std::ofstream(dataset / "pass1" / "depth" / "0.000000.png") << std::string(499, 'd') << 'e';  // same size
  const CachedDatasetCheck sizes_only = CheckCachedDataset(dataset);
  EXPECT_FALSE(sizes_only.hashed);  // this process hashed it already
  EXPECT_TRUE(sizes_only.problems.empty());
  const CachedDatasetCheck verified = CheckCachedDataset(dataset, /*always_hash=*/true);
  EXPECT_TRUE(verified.hashed);
  ASSERT_EQ(verified.problems.size(), 1u);
  EXPECT_NE(verified.problems[0].find("pass1/depth/0.000000.png"), std::string::npos) << verified.problems[0];

  fs::remove(dataset / "pass1" / "rgb.txt");
  const CachedDatasetCheck missing = CheckCachedDataset(dataset);
  ASSERT_EQ(missing.problems.size(), 1u);
  EXPECT_NE(missing.problems[0].find("pass1/rgb.txt"), std::string::npos) << missing.problems[0];
}

}  // namespace
}  // namespace segslam::harness
