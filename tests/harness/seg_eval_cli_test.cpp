// `segslam seg-eval` on generated sequences (fixture sim_datasets): the paper's Tables II
// and IV with ground-truth poses, from the simulated segmenter or from an external mask
// folder, written as seg_eval.json and the last frame's overlays; the same seed gives the
// same scores and pictures; refused input leaves no output folder.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/harness/cli_runner.h"

namespace {

namespace fs = std::filesystem;
using segslam::testing::CommandOutput;
using segslam::testing::ReadText;

const fs::path kDataDir = SEGSLAM_TEST_DATA_DIR;

class SegEvalCliTest : public segslam::testing::CliScratchTest {
 protected:
  SegEvalCliTest() : CliScratchTest("segslam_seg_eval_") {}

  nlohmann::json RunAndReadJson(const std::string& arguments, const fs::path& out_dir) {
    const CommandOutput out = Run("seg-eval " + arguments + " --out " + out_dir.string());
    EXPECT_EQ(out.exit_code, 0) << out.stderr_text;
    return nlohmann::json::parse(ReadText(out_dir / "seg_eval.json"));
  }
};

TEST_F(SegEvalCliTest, ScoresBothPassesAndDrawsTheirLastFrames) {
  const fs::path dataset = kDataDir / "office_clean";
  ASSERT_TRUE(fs::is_directory(dataset / "pass1")) << dataset;
  const fs::path out_dir = dir_ / "out";
  const CommandOutput out = Run("seg-eval " + dataset.string() + " --out " + out_dir.string());
  ASSERT_EQ(out.exit_code, 0) << out.stderr_text;

  const nlohmann::json json = nlohmann::json::parse(ReadText(out_dir / "seg_eval.json"));
  EXPECT_EQ(json.at("poses"), "gt");
  EXPECT_EQ(json.at("seed"), 1);
  ASSERT_EQ(json.at("sequences").size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const nlohmann::json& sequence = json.at("sequences")[k];
    const std::string name = k == 0 ? "pass1" : "pass2";
    SCOPED_TRACE(name);
    EXPECT_EQ(sequence.at("sequence"), name);
    EXPECT_EQ(sequence.at("frames"), 40);
    for (const char* stage : {"raw", "refined"}) {
      for (const char* metric : {"mAP", "AP50", "mIoU"}) {
        const double value = sequence.at(stage).at(metric).get<double>();
        EXPECT_GT(value, 0.0) << stage << " " << metric;
        EXPECT_LE(value, 1.0) << stage << " " << metric;
      }
    }
    // The fcis-like segmenter's bleeding and holes are what the refinement repairs.
    EXPECT_GT(sequence.at("refined").at("mIoU").get<double>(), sequence.at("raw").at("mIoU").get<double>());
    // Every region of every frame gets one decision; the first frame's are all new.
    int decisions = 0;
    for (const auto& [kind, count] : sequence.at("decisions").items()) decisions += count.get<int>();
    EXPECT_GE(sequence.at("decisions").at("new").get<int>(), 1);
    EXPECT_GT(decisions, 40);

    // The paper's Fig. 5: ground truth, initial and refined side by side, captioned.
    const cv::Mat overlay = cv::imread((out_dir / (name + "_last_frame.png")).string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(overlay.empty()) << name << "_last_frame.png";
    EXPECT_EQ(overlay.cols, 3 * 640);
    EXPECT_EQ(overlay.rows, 480);
    // The table prints a row per pass.
    EXPECT_NE(out.stdout_text.find("\n" + name + " "), std::string::npos) << out.stdout_text;
  }
}

TEST_F(SegEvalCliTest, TheSameSeedGivesTheSameScoresAndPicturesAnotherSeedOthers) {
  const fs::path sequence = kDataDir / "office_clean" / "pass1";
  ASSERT_TRUE(fs::is_directory(sequence)) << sequence;
  const nlohmann::json first = RunAndReadJson(sequence.string() + " --seed 5", dir_ / "a");
  RunAndReadJson(sequence.string() + " --seed 5", dir_ / "b");
  const nlohmann::json other = RunAndReadJson(sequence.string() + " --seed 6", dir_ / "c");
  // The same scores to the last digit; only the refinement's time may differ.
  nlohmann::json first_scores = first, second_scores = nlohmann::json::parse(ReadText(dir_ / "b" / "seg_eval.json"));
  for (nlohmann::json* json : {&first_scores, &second_scores}) json->at("sequences")[0].erase("refine_ms_median");
  EXPECT_EQ(first_scores.dump(), second_scores.dump());
  EXPECT_EQ(ReadText(dir_ / "a" / "pass1_last_frame.png"), ReadText(dir_ / "b" / "pass1_last_frame.png"));
  // One sequence given directly: one row, named after its folder.
  ASSERT_EQ(first.at("sequences").size(), 1u);
  EXPECT_EQ(first.at("sequences")[0].at("sequence"), "pass1");
  EXPECT_NE(first.at("sequences")[0].at("raw").at("mIoU"), other.at("sequences")[0].at("raw").at("mIoU"));
}

// The clean preset is the ground truth; refining it with the true poses must keep it.
TEST_F(SegEvalCliTest, CleanSegmenterScoresPerfectAndRefinementKeepsIt) {
  const fs::path sequence = kDataDir / "office_clean" / "pass1";
  ASSERT_TRUE(fs::is_directory(sequence)) << sequence;
  const nlohmann::json json = RunAndReadJson(sequence.string() + " --segmenter clean", dir_ / "out");
  const nlohmann::json& scores = json.at("sequences")[0];
  for (const char* metric : {"mAP", "AP50", "mIoU"}) {
    EXPECT_DOUBLE_EQ(scores.at("raw").at(metric).get<double>(), 1.0) << metric;
  }
  EXPECT_GE(scores.at("refined").at("mIoU").get<double>(), 0.99);

  // Pass 2 has walkers whose regions grow fast. The trim keeps what lies at the region's
  // depth, so the masks stay whole (mAP 99.9995 %: one region a few pixels short in one
  // frame); the plain trim (the option off) cuts a walker back to the last frame's
  // extent (mAP 99.5 %).
  const fs::path pass2 = kDataDir / "office_clean" / "pass2";
  const nlohmann::json kept = RunAndReadJson(pass2.string() + " --segmenter clean", dir_ / "kept");
  for (const char* metric : {"mAP", "AP50", "mIoU"}) {
    EXPECT_GT(kept.at("sequences")[0].at("refined").at(metric).get<double>(), 0.9999) << metric;
  }
  const nlohmann::json cut =
      RunAndReadJson(pass2.string() + " --segmenter clean --refiner trim_keeps_region_depth=0", dir_ / "cut");
  EXPECT_LT(cut.at("sequences")[0].at("refined").at("mAP").get<double>(),
            kept.at("sequences")[0].at("refined").at("mAP").get<double>() - 0.002);
}

// Masks of an external segmenter, here the ground truth itself written in the external
// layout (seg/external_masks.h): the raw scores are perfect, and the table names the folder.
TEST_F(SegEvalCliTest, ExternalMasksReplaceTheSimulatedSegmenter) {
  const fs::path sequence = kDataDir / "office_clean" / "pass1";
  ASSERT_TRUE(fs::is_directory(sequence)) << sequence;
  const nlohmann::json ground_truth_table = nlohmann::json::parse(ReadText(sequence / "instances.json"));
  nlohmann::json table = {{"instances", nlohmann::json::array()}};
  for (const nlohmann::json& instance : ground_truth_table.at("instances")) {
    table["instances"].push_back({{"id", instance.at("id")}, {"category_id", instance.at("category_id")}});
  }
  const fs::path masks = dir_ / "masks";
  fs::create_directories(masks);
  int frames = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(sequence / "masks")) {
    fs::copy_file(entry.path(), masks / entry.path().filename());
    std::ofstream(masks / (entry.path().stem().string() + ".json")) << table.dump();
    ++frames;
  }
  ASSERT_EQ(frames, 40);

  const CommandOutput out =
      Run("seg-eval " + sequence.string() + " --masks " + masks.string() + " --out " + (dir_ / "out").string());
  ASSERT_EQ(out.exit_code, 0) << out.stderr_text;
  EXPECT_NE(out.stdout_text.find("external masks " + masks.string()), std::string::npos) << out.stdout_text;
  const nlohmann::json json = nlohmann::json::parse(ReadText(dir_ / "out" / "seg_eval.json"));
  const nlohmann::json& scores = json.at("sequences")[0];
  EXPECT_EQ(scores.at("frames"), 40);
  for (const char* metric : {"mAP", "AP50", "mIoU"}) {
    EXPECT_DOUBLE_EQ(scores.at("raw").at(metric).get<double>(), 1.0) << metric;
  }

  // A folder that skips a frame does not match the sequence: named, and nothing written.
  fs::remove(masks / "0.033333.png");
  const CommandOutput skipped =
      Run("seg-eval " + sequence.string() + " --masks " + masks.string() + " --out " + (dir_ / "out2").string());
  EXPECT_EQ(skipped.exit_code, 1);
  EXPECT_NE(skipped.stderr_text.find("0.033333.png"), std::string::npos) << skipped.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "out2"));
}

TEST_F(SegEvalCliTest, RefusedInputIsNamedAndLeavesNoOutputFolder) {
  const fs::path sequence = kDataDir / "office_clean" / "pass1";
  ASSERT_TRUE(fs::is_directory(sequence)) << sequence;
  const struct {
    std::string arguments, message;
  } cases[] = {
      {"--poses slam", "only 'gt' is available"},
      {"--refiner no_such_option=1", "unknown field 'no_such_option'"},
      {"--refiner w_shape=abc", "not a number: 'abc'"},
      {"--segmenter no-such-preset", "unknown simulated segmenter preset 'no-such-preset'"},
      {"--masks " + (dir_ / "missing").string(), "external masks folder does not exist"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.arguments);
    const fs::path out_dir = dir_ / "out";
    const CommandOutput out = Run("seg-eval " + sequence.string() + " " + c.arguments + " --out " + out_dir.string());
    EXPECT_EQ(out.exit_code, 1);
    EXPECT_NE(out.stderr_text.find(c.message), std::string::npos) << out.stderr_text;
    EXPECT_FALSE(fs::exists(out_dir));
  }
  const CommandOutput missing = Run("seg-eval " + (dir_ / "no_dataset").string() + " --out " + (dir_ / "out").string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.stderr_text.find("no_dataset: sequence directory does not exist"), std::string::npos)
      << missing.stderr_text;
}

// One pose per frame, but at other stamps (a trajectory cut to the frame count): refused,
// naming the pose and the frame, instead of pairing poses with the wrong frames.
TEST_F(SegEvalCliTest, GroundTruthAtOtherStampsIsRefused) {
  const fs::path original = kDataDir / "office_clean" / "pass1";
  ASSERT_TRUE(fs::is_directory(original)) << original;
  const fs::path sequence = dir_ / "sequence";
  fs::create_directories(sequence);
  for (const auto& entry : fs::directory_iterator(original)) {
    if (entry.is_directory()) {
      fs::create_directory_symlink(entry.path(), sequence / entry.path().filename());
    } else if (entry.path().filename() != "groundtruth.txt") {
      fs::copy_file(entry.path(), sequence / entry.path().filename());
    }
  }
  // The same poses, 0.25 s later each.
  std::ifstream in(original / "groundtruth.txt");
  std::ofstream out(sequence / "groundtruth.txt");
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const size_t space = line.find(' ');
    out << std::fixed << std::stod(line.substr(0, space)) + 0.25 << line.substr(space) << "\n";
  }
  out.close();
  const CommandOutput refused = Run("seg-eval " + sequence.string() + " --out " + (dir_ / "out").string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.stderr_text.find("pose 0 is at 0.250000 s, frame 0 at 0.000000 s"), std::string::npos)
      << refused.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

}  // namespace
