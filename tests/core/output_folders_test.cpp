// Recognising segslam's output folders (core/output_folders.h): what --force and re-runs
// may replace, and the first file of anything else, named.
#include "core/output_folders.h"

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "core/manifest.h"
#include "test_util.h"

namespace segslam {
namespace {

namespace fs = std::filesystem;

class OutputFoldersTest : public testing::TempDirTest {
 protected:
  void Write(const fs::path& file, const std::string& text = "x") {
    fs::create_directories(file.parent_path());
    std::ofstream(file) << text;
  }

  // A dataset as generate writes it: files, then the manifest listing them.
  fs::path MakeDataset() {
    const fs::path dataset = dir() / "dataset";
    Write(dataset / "pass1" / "rgb" / "0.000000.png");
    Write(dataset / "pass1" / "rgb.txt");
    Write(dataset / "scenario.yaml");
    WriteManifest(dataset, {});
    return dataset;
  }

  fs::path MakeRun(const fs::path& run) {
    Write(run / "run.json", R"({"format": "segslam-run-1"})");
    for (const char* pass : {"pass1", "pass2"}) {
      Write(run / pass / "trajectory.txt", "# segslam run, mode plain\n");
      Write(run / pass / "frames.jsonl");
      Write(run / pass / "refined_masks" / "0.000000.png");
      Write(run / pass / "refined_masks" / kMaskFolderRecordFile, "{}");
    }
    Write(run / "pass1" / "map.segslam");
    Write(run / "pass1" / "map.ply");
    return run;
  }
};

TEST_F(OutputFoldersTest, ADatasetIsKnownByItsManifestAndAnUnlistedFileIsNamed) {
  const fs::path dataset = MakeDataset();
  EXPECT_EQ(ForeignContentOfDataset(dataset), "");
  MakeRun(dataset / "run_plain");  // `run`'s default output lies inside the dataset
  EXPECT_EQ(ForeignContentOfDataset(dataset), "");

  Write(dataset / "pass1" / "notes" / "t.tex");
  EXPECT_EQ(ForeignContentOfDataset(dataset), "pass1/notes/t.tex is in no manifest.json");
  fs::remove_all(dataset / "pass1" / "notes");
  Write(dataset / "run_plain" / "thesis.tex");  // no longer a run's folder: its files count
  EXPECT_EQ(ForeignContentOfDataset(dataset).find("run_plain/"), 0u) << ForeignContentOfDataset(dataset);

  const fs::path folder = dir() / "folder";
  Write(folder / "manifest.json", R"({"files": []})");  // not segslam's manifest
  EXPECT_EQ(ForeignContentOfDataset(folder), "no segslam manifest.json");
}

TEST_F(OutputFoldersTest, ARunOutputHoldsOnlyWhatARunWrites) {
  const fs::path run = MakeRun(dir() / "run");
  EXPECT_EQ(ForeignContentOfRunOutput(run), "");
  Write(run / "pass2" / "notes.txt");
  EXPECT_EQ(ForeignContentOfRunOutput(run), "pass2/notes.txt is no file of a run");
  fs::remove(run / "pass2" / "notes.txt");
  fs::create_directories(run / "plots");
  EXPECT_EQ(ForeignContentOfRunOutput(run), "plots/ is no folder of a run");
  fs::remove(run / "plots");

  // A run of a build before run.json, known by its trajectory's header.
  fs::remove(run / "run.json");
  EXPECT_EQ(ForeignContentOfRunOutput(run), "");
  Write(run / "pass1" / "trajectory.txt", "1.0 0 0 0 0 0 0 1\n");
  EXPECT_EQ(ForeignContentOfRunOutput(run), "no run.json of segslam run");
}

TEST_F(OutputFoldersTest, AMaskFolderHoldsItsRecordAndMasksOnly) {
  const fs::path masks = dir() / "masks";
  Write(masks / "0.000000.png");
  Write(masks / "0.000000.json");
  EXPECT_EQ(ForeignContentOfMaskFolder(masks), std::string("no ") + kMaskFolderRecordFile);
  Write(masks / kMaskFolderRecordFile, "{}");
  EXPECT_EQ(ForeignContentOfMaskFolder(masks), "");
  Write(masks / "sub" / "t.tex");
  EXPECT_EQ(ForeignContentOfMaskFolder(masks), "sub is no file of a mask folder");
}

}  // namespace
}  // namespace segslam
