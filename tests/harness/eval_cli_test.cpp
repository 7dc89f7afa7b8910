// `segslam eval` on runs of a generated dataset (fixture sim_datasets): the same ATE as
// `segslam run` printed, and one-line errors for a dataset without ground truth, a run
// folder without trajectory and a run of another sequence.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/harness/cli_runner.h"

namespace {

namespace fs = std::filesystem;
using segslam::testing::CommandOutput;
using segslam::testing::LineCount;
using segslam::testing::ReadText;

const fs::path kDataDir = SEGSLAM_TEST_DATA_DIR;

class EvalCliTest : public segslam::testing::CliScratchTest {
 protected:
  EvalCliTest() : CliScratchTest("segslam_eval_") {}
};

// The fields of the row of `segslam run`'s table that starts with `name`.
std::vector<std::string> RowFields(const std::string& table, const std::string& name) {
  std::istringstream lines(table);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(name + " ", 0) != 0) continue;
    std::istringstream fields(line);
    std::vector<std::string> result;
    for (std::string field; fields >> field;) result.push_back(field);
    return result;
  }
  ADD_FAILURE() << "no row '" << name << "' in:\n" << table;
  return {};
}

void WriteText(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file) << text;
}

TEST_F(EvalCliTest, GivesTheAteThatRunPrinted) {
  const fs::path dataset = kDataDir / "office_seg";
  ASSERT_TRUE(fs::is_directory(dataset)) << dataset << " missing: ctest's sim_datasets fixture makes it";
  const fs::path run_dir = dir_ / "run";
  const CommandOutput run = Run("run " + dataset.string() + " --mode mutual --segmenter fcis-like --seed 3 --frames 30 -q --out " +
                                run_dir.string());
  ASSERT_EQ(run.exit_code, 0) << run.stderr_text;
  std::printf("%s", run.stdout_text.c_str());

  const fs::path json_file = dir_ / "eval.json";
  const CommandOutput eval = Run("eval " + run_dir.string() + " --dataset " + dataset.string() + " --json " + json_file.string());
  ASSERT_EQ(eval.exit_code, 0) << eval.stderr_text;
  std::printf("%s", eval.stdout_text.c_str());
  const nlohmann::json json = nlohmann::json::parse(ReadText(json_file));
  ASSERT_EQ(json["passes"].size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const nlohmann::json& pass = json["passes"][i];
    const std::string name = pass["name"];
    // sequence frames localized keyframes points track-ms ATE-rmse ATE-max ...
    const std::vector<std::string> printed = RowFields(run.stdout_text, name);
    ASSERT_GE(printed.size(), 8u);
    EXPECT_EQ(pass["frames"].get<int>(), std::stoi(printed[1]));
    // run prints 4 decimals; eval re-reads the written trajectory (9 digits).
    EXPECT_NEAR(pass["ate"]["translation_m"]["rmse"].get<double>(), std::stod(printed[6]), 5.1e-5) << name;
    EXPECT_NEAR(pass["ate"]["translation_m"]["max"].get<double>(), std::stod(printed[7]), 5.1e-5) << name;
    EXPECT_EQ(pass["ate"]["aligned"].get<bool>(), name == "pass1");
    EXPECT_NEAR(100 * pass["localized_share"].get<double>(), std::stod(printed[2]), 0.051);
    // The mutual loop scored its masks; eval reports seg.json's figures.
    const nlohmann::json seg = nlohmann::json::parse(ReadText(run_dir / name / "seg.json"));
    EXPECT_EQ(pass["segmentation"]["raw"]["mAP"], seg["raw"]["mAP"]);
    EXPECT_EQ(pass["segmentation"]["refined"]["mIoU"], seg["refined"]["mIoU"]);
    EXPECT_TRUE(pass["moving_detection"].is_object());
  }
  EXPECT_NE(eval.stdout_text.find("map frame"), std::string::npos);
  // Pass 2 is also scored against pass 1's estimate at the same place (map-relative).
  EXPECT_TRUE(json["passes"][0]["map_relative"].is_null());
  const nlohmann::json& map_relative = json["passes"][1]["map_relative"];
  ASSERT_TRUE(map_relative.is_object()) << json["passes"][1].dump(2);
  EXPECT_EQ(map_relative["frames_with_place"].get<int>() + map_relative["frames_without_place"].get<int>() +
                map_relative["frames_without_ground_truth"].get<int>(),
            json["passes"][1]["frames"].get<int>());
  EXPECT_EQ(json["passes"][1]["metrics"]["reloc_within_share"], map_relative["within_share"]);
  EXPECT_NE(eval.stdout_text.find("Map-relative relocalization error"), std::string::npos);
}

TEST_F(EvalCliTest, DatasetWithoutGroundTruthIsOneLine) {
  WriteText(dir_ / "sequence" / "rgb.txt", "0.000000 rgb/0.000000.png\n");
  WriteText(dir_ / "run" / "trajectory.txt", "0.000000 0 0 0 0 0 0 1\n");
  WriteText(dir_ / "run" / "frames.jsonl", "{\"frame\": 0, \"stamp\": 0.0, \"status\": \"tracking\", \"instances\": []}\n");
  const CommandOutput eval = Run("eval " + (dir_ / "run").string() + " --dataset " + (dir_ / "sequence").string());
  EXPECT_EQ(eval.exit_code, 1);
  EXPECT_EQ(LineCount(eval.stderr_text), 1) << eval.stderr_text;
  EXPECT_NE(eval.stderr_text.find("eval: " + (dir_ / "sequence" / "groundtruth.txt").string() + ": no ground truth"),
            std::string::npos)
      << eval.stderr_text;
}

// A sequence that lists its frames in associations.txt only (no rgb.txt, depth.txt), as
// TumSequence reads one, is scored as well as run.
TEST_F(EvalCliTest, SequenceWithOnlyAssociationsIsScored) {
  const fs::path original = kDataDir / "office_seg" / "pass1";
  ASSERT_TRUE(fs::is_directory(original)) << original << " missing: ctest's sim_datasets fixture makes it";
  const fs::path sequence = dir_ / "sequence";
  fs::create_directories(sequence);
  for (const char* file : {"associations.txt", "groundtruth.txt", "camera.yaml"}) {
    fs::copy_file(original / file, sequence / file);
  }
  for (const char* folder : {"rgb", "depth"}) fs::create_directory_symlink(original / folder, sequence / folder);
  const CommandOutput run =
      Run("run " + sequence.string() + " --mode plain --frames 15 -q --out " + (dir_ / "run").string());
  ASSERT_EQ(run.exit_code, 0) << run.stderr_text;
  const CommandOutput eval = Run("eval " + (dir_ / "run").string() + " --dataset " + sequence.string());
  EXPECT_EQ(eval.exit_code, 0) << eval.stderr_text;
}

TEST_F(EvalCliTest, RunFolderWithoutTrajectoryIsOneLine) {
  const fs::path dataset = kDataDir / "office_seg";
  ASSERT_TRUE(fs::is_directory(dataset)) << dataset << " missing: ctest's sim_datasets fixture makes it";
  fs::create_directories(dir_ / "run" / "pass1");
  fs::create_directories(dir_ / "run" / "pass2");
  const fs::path json_file = dir_ / "eval.json";
  const CommandOutput eval =
      Run("eval " + (dir_ / "run").string() + " --dataset " + dataset.string() + " --json " + json_file.string());
  EXPECT_EQ(eval.exit_code, 1);
  EXPECT_EQ(LineCount(eval.stderr_text), 1) << eval.stderr_text;
  EXPECT_NE(eval.stderr_text.find((dir_ / "run" / "pass1" / "trajectory.txt").string() + ": no trajectory"),
            std::string::npos)
      << eval.stderr_text;
  EXPECT_FALSE(fs::exists(json_file));
}

TEST_F(EvalCliTest, RunOfAnotherSequenceIsRefused) {
  const fs::path sequence = kDataDir / "office_seg" / "pass1";
  ASSERT_TRUE(fs::is_directory(sequence)) << sequence << " missing: ctest's sim_datasets fixture makes it";
  WriteText(dir_ / "run" / "trajectory.txt", "12345.5 0 0 0 0 0 0 1\n");
  WriteText(dir_ / "run" / "frames.jsonl",
            "{\"frame\": 0, \"stamp\": 12345.5, \"status\": \"tracking\", \"instances\": []}\n");
  CommandOutput eval = Run("eval " + (dir_ / "run").string() + " --dataset " + sequence.string());
  EXPECT_EQ(eval.exit_code, 1);
  EXPECT_EQ(LineCount(eval.stderr_text), 1) << eval.stderr_text;
  EXPECT_NE(eval.stderr_text.find("the run is of another sequence"), std::string::npos) << eval.stderr_text;
  // A single-sequence run against a two-pass dataset.
  eval = Run("eval " + (dir_ / "run").string() + " --dataset " + (kDataDir / "office_seg").string());
  EXPECT_EQ(eval.exit_code, 1);
  EXPECT_NE(eval.stderr_text.find("run and dataset do not match"), std::string::npos) << eval.stderr_text;
}

// Two generated worlds of one frame rate share every stamp: a run of one office world was
// scored against another's dataset (ATE 0.064 m for a true 0.0047 m). A run records the
// first colour file it read and its SHA-256 (run.json), and eval refuses another sequence.
TEST_F(EvalCliTest, RunOfAnotherWorldWithTheSameStampsIsRefused) {
  const fs::path scenario = fs::path(SEGSLAM_SOURCE_DIR) / "scenarios" / "test" / "office_small.yaml";
  const fs::path world_a = dir_ / "world_a", world_b = dir_ / "world_b";
  ASSERT_EQ(Run("generate " + scenario.string() + " --frames 5 -q --out " + world_a.string()).exit_code, 0);
  ASSERT_EQ(Run("generate " + scenario.string() + " --frames 5 -q --set seed=9 --out " + world_b.string()).exit_code, 0);
  ASSERT_EQ(ReadText(world_a / "pass1" / "associations.txt"), ReadText(world_b / "pass1" / "associations.txt"));

  const fs::path run_dir = dir_ / "run";
  const CommandOutput run = Run("run " + (world_a / "pass1").string() + " --mode plain -q --out " + run_dir.string());
  ASSERT_EQ(run.exit_code, 0) << run.stderr_text;
  const CommandOutput own = Run("eval " + run_dir.string() + " --dataset " + (world_a / "pass1").string());
  EXPECT_EQ(own.exit_code, 0) << own.stderr_text;
  const CommandOutput other = Run("eval " + run_dir.string() + " --dataset " + (world_b / "pass1").string());
  EXPECT_EQ(other.exit_code, 1);
  EXPECT_EQ(LineCount(other.stderr_text), 1) << other.stderr_text;
  EXPECT_NE(other.stderr_text.find("eval: " + run_dir.string() + " is a run of " + (world_a / "pass1").string() +
                                   ", not of " + (world_b / "pass1").string() +
                                   ": the first colour frame it read, rgb/0.000000.png, differs from"),
            std::string::npos)
      << other.stderr_text;

  // Both passes of a generated dataset: each pass is checked.
  const CommandOutput both = Run("run " + world_a.string() + " --mode plain -q --out " + run_dir.string());
  ASSERT_EQ(both.exit_code, 0) << both.stderr_text;
  const CommandOutput other_both = Run("eval " + run_dir.string() + " --dataset " + world_b.string());
  EXPECT_EQ(other_both.exit_code, 1);
  EXPECT_NE(other_both.stderr_text.find("is a run of " + (world_a / "pass1").string()), std::string::npos)
      << other_both.stderr_text;
}

}  // namespace
