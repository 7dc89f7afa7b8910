// `segslam bench render` on a small scenario, and `segslam bench slam` on a generated
// sequence (fixture sim_datasets): the per-stage table and its JSON hold a time for every
// stage and the keyframes' bundle adjustment, with a segmenter the mask refinement's too,
// and a sequence without camera intrinsics needs --camera. Speed itself is what the
// command measures, so nothing here asserts how fast.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include "tests/harness/cli_runner.h"

namespace {

namespace fs = std::filesystem;
using segslam::testing::CommandOutput;
using segslam::testing::ReadText;

const fs::path kDataDir = SEGSLAM_TEST_DATA_DIR;

class BenchCliTest : public segslam::testing::CliScratchTest {
 protected:
  BenchCliTest() : CliScratchTest("segslam_bench_") {}
};

TEST_F(BenchCliTest, SlamTimesEveryStageAndTheBundleAdjustment) {
  const fs::path sequence = kDataDir / "office_static" / "pass1";
  ASSERT_TRUE(fs::is_directory(sequence)) << sequence;
  const fs::path json_file = dir_ / "bench.json";
  const CommandOutput out =
      Run("bench slam " + sequence.string() + " --mode plain --frames 30 --json " + json_file.string());
  ASSERT_EQ(out.exit_code, 0) << out.stderr_text;
  for (const char* row : {"features", "coarse", "judge", "fine", "map update", "tracking total",
                          "bundle adj. per keyframe"}) {
    EXPECT_NE(out.stdout_text.find(row), std::string::npos) << row << " missing from:\n" << out.stdout_text;
  }
  const nlohmann::json json = nlohmann::json::parse(ReadText(json_file));
  EXPECT_EQ(json.at("frames"), 30);
  EXPECT_EQ(json.at("mode"), "plain");
  // Times mean little without the machine they were taken on.
  EXPECT_GE(json.at("machine").at("cores").get<unsigned>(), 1u);
  EXPECT_NE(out.stdout_text.find(" cores\n"), std::string::npos) << out.stdout_text;
  const nlohmann::json& stages = json.at("stages_ms");
  EXPECT_GT(stages.at("features").at("median").get<double>(), 0.0);
  EXPECT_GT(stages.at("coarse").at("median").get<double>(), 0.0);
  EXPECT_EQ(stages.at("judge").at("median").get<double>(), 0.0) << "plain mode judges nothing";
  const double total = stages.at("tracking total").at("median").get<double>();
  EXPECT_GE(total, stages.at("features").at("median").get<double>());
  // The camera moves 30 frames: more than the first keyframe, each bundle-adjusted.
  const nlohmann::json& ba = json.at("bundle_adjustment_per_keyframe_ms");
  EXPECT_GE(ba.at("keyframes").get<int>(), 1);
  EXPECT_GT(ba.at("median").get<double>(), 0.0);
}

// With a segmenter, mutual runs the paper's whole loop: the masks' refinement is timed
// beside tracking; a segmenter and an external folder together are refused.
TEST_F(BenchCliTest, MutualLoopWithASegmenterTimesTheMaskRefinement) {
  const fs::path sequence = kDataDir / "office_seg" / "pass1";
  ASSERT_TRUE(fs::is_directory(sequence)) << sequence;
  const fs::path json_file = dir_ / "bench.json";
  const CommandOutput out = Run("bench slam " + sequence.string() +
                                " --mode mutual --segmenter fcis-like --frames 12 --json " + json_file.string());
  ASSERT_EQ(out.exit_code, 0) << out.stderr_text;
  EXPECT_NE(out.stdout_text.find("masks simulated fcis-like seed 1"), std::string::npos) << out.stdout_text;
  EXPECT_NE(out.stdout_text.find("mask refinement"), std::string::npos) << out.stdout_text;
  const nlohmann::json json = nlohmann::json::parse(ReadText(json_file));
  EXPECT_EQ(json.at("masks"), "simulated fcis-like seed 1");
  EXPECT_GT(json.at("stages_ms").at("mask refinement").at("median").get<double>(), 0.0);
  EXPECT_GT(json.at("stages_ms").at("judge").at("median").get<double>(), 0.0);
  // The loop without the segmenter: each frame's tracking plus its refinement, so its
  // median lies above both medians (each frame's sum exceeds either part).
  const double loop = json.at("stages_ms").at("loop (tracking+refinement)").at("median").get<double>();
  EXPECT_GT(loop, json.at("stages_ms").at("mask refinement").at("median").get<double>());
  EXPECT_GT(loop, json.at("stages_ms").at("tracking total").at("median").get<double>());

  const CommandOutput gt = Run("bench slam " + sequence.string() + " --mode mutual --frames 3");
  ASSERT_EQ(gt.exit_code, 0) << gt.stderr_text;
  EXPECT_EQ(gt.stdout_text.find("mask refinement"), std::string::npos) << "no segmenter, no loop";

  const CommandOutput both =
      Run("bench slam " + sequence.string() + " --mode mutual --segmenter clean --masks " + dir_.string());
  EXPECT_EQ(both.exit_code, 1);
  EXPECT_NE(both.stderr_text.find("exclude each other"), std::string::npos) << both.stderr_text;
}

// --tracker and --refiner measure other settings: the features requested follow
// orb.max_features, and the overrides are printed and kept in the JSON.
TEST_F(BenchCliTest, SlamTakesTrackerAndRefinerOptions) {
  const fs::path sequence = kDataDir / "office_seg" / "pass1";
  ASSERT_TRUE(fs::is_directory(sequence)) << sequence;
  const fs::path json_file = dir_ / "bench.json";
  const CommandOutput out =
      Run("bench slam " + sequence.string() + " --mode mutual --segmenter fcis-like --frames 6 --tracker orb.max_features=500" +
          " --refiner trim_keeps_region_depth=0 --json " + json_file.string());
  ASSERT_EQ(out.exit_code, 0) << out.stderr_text;
  EXPECT_NE(out.stdout_text.find("500 features requested"), std::string::npos) << out.stdout_text;
  EXPECT_NE(out.stdout_text.find("refiner options: trim_keeps_region_depth=0"), std::string::npos) << out.stdout_text;
  const nlohmann::json json = nlohmann::json::parse(ReadText(json_file));
  EXPECT_EQ(json.at("features_requested"), 500);
  EXPECT_EQ(json.at("tracker_options"), nlohmann::json::array({"orb.max_features=500"}));
  EXPECT_EQ(json.at("refiner_options"), nlohmann::json::array({"trim_keeps_region_depth=0"}));

  for (const auto& [arguments, message] :
       {std::pair<std::string, std::string>{" --mode plain --refiner depth_tolerance=0.1", "applies to the mutual loop"},
        {" --mode mutual --segmenter clean --refiner depth_tolerance=2", "depth_tolerance: 2 is outside its range [0, 1)"},
        {" --mode plain --tracker orb.max_feature=500", "unknown field 'orb.max_feature'"}}) {
    const CommandOutput refused = Run("bench slam " + sequence.string() + arguments);
    EXPECT_EQ(refused.exit_code, 1) << arguments;
    EXPECT_NE(refused.stderr_text.find(message), std::string::npos) << arguments << ": " << refused.stderr_text;
  }
}

TEST_F(BenchCliTest, SlamOnASequenceWithoutCameraNeedsCamera) {
  const fs::path source = kDataDir / "office_static" / "pass1";
  ASSERT_TRUE(fs::is_directory(source)) << source;
  const fs::path copy = dir_ / "sequence";
  fs::copy(source, copy, fs::copy_options::recursive);
  const fs::path camera = dir_ / "camera.yaml";
  fs::rename(copy / "camera.yaml", camera);
  const CommandOutput refused = Run("bench slam " + copy.string() + " --mode plain --frames 3");
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.stderr_text.find((copy / "camera.yaml").string()), std::string::npos) << refused.stderr_text;
  const CommandOutput given = Run("bench slam " + copy.string() + " --mode plain --frames 3 --camera " + camera.string());
  EXPECT_EQ(given.exit_code, 0) << given.stderr_text;
}

// `segslam bench render` generates and renders a small scenario with each back-end (on a
// machine without a GPU both run on Mesa's llvmpipe) and removes its scratch datasets.
TEST_F(BenchCliTest, RenderMeasuresEachBackEndAndLeavesNoScratch) {
  const fs::path scenario = fs::path(SEGSLAM_SOURCE_DIR) / "scenarios" / "test" / "office_small.yaml";
  const fs::path work_dir = dir_ / "work";
  fs::create_directories(work_dir);
  const fs::path json_file = dir_ / "render.json";
  const CommandOutput out = Run("bench render " + scenario.string() + " --frames 2 --work-dir " + work_dir.string() +
                                " --json " + json_file.string());
  ASSERT_EQ(out.exit_code, 0) << out.stderr_text;
  EXPECT_NE(out.stdout_text.find("office_small (320x240), 4 frames per back-end"), std::string::npos)
      << out.stdout_text;
  const nlohmann::json json = nlohmann::json::parse(ReadText(json_file));
  EXPECT_EQ(json.at("scenario"), "office_small");
  ASSERT_EQ(json.at("backends").size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    const nlohmann::json& backend = json.at("backends")[k];
    SCOPED_TRACE(backend.dump());
    EXPECT_EQ(backend.at("backend"), k == 0 ? "osmesa" : "egl");
    EXPECT_EQ(backend.at("frames"), 4) << "2 frames in each of the two passes";
    EXPECT_GT(backend.at("generation_fps").get<double>(), 0.0);
    EXPECT_GT(backend.at("render_only_fps").get<double>(), 0.0);
    EXPECT_FALSE(backend.at("renderer").get<std::string>().empty());
    EXPECT_NE(out.stdout_text.find(backend.at("renderer").get<std::string>()), std::string::npos);
  }
  EXPECT_TRUE(fs::is_empty(work_dir)) << "scratch datasets left in " << work_dir;

  const CommandOutput unknown = Run("bench render " + scenario.string() + " --gl vulkan");
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_NE(unknown.stderr_text.find("vulkan"), std::string::npos) << unknown.stderr_text;
}

}  // namespace
