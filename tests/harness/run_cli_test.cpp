// `segslam run`'s options that tune the mutual loop, on the generated office fixture.
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

class RunCliTest : public segslam::testing::CliScratchTest {
 protected:
  RunCliTest() : CliScratchTest("segslam_run_") {}

  nlohmann::json RunLoopAndReadSegJson(const std::string& extra, const fs::path& out_dir) {
    const fs::path sequence = kDataDir / "office_seg" / "pass1";
    EXPECT_TRUE(fs::is_directory(sequence)) << sequence << " missing: ctest's sim_datasets fixture makes it";
    last_ = Run("run " + sequence.string() + " --mode mutual --segmenter fcis-like --seed 2 --frames 20 -q --out " +
                out_dir.string() + " " + extra);
    EXPECT_EQ(last_.exit_code, 0) << last_.stderr_text;
    return nlohmann::json::parse(ReadText(out_dir / "seg.json"));
  }
  CommandOutput last_;
};

// The default refinement adds the projection of an instance the segmenter missed;
// add_unmatched=0 (never) must reach the loop and add none, the raw masks unchanged.
TEST_F(RunCliTest, RefinerOptionsReachTheLoop) {
  const nlohmann::json by_default = RunLoopAndReadSegJson("", dir_ / "default");
  EXPECT_EQ(last_.stdout_text.find("with add_unmatched"), std::string::npos);
  const nlohmann::json never_added = RunLoopAndReadSegJson("--refiner add_unmatched=0", dir_ / "never_added");
  EXPECT_NE(last_.stdout_text.find("refined in the loop with add_unmatched=0"), std::string::npos) << last_.stdout_text;
  EXPECT_GT(by_default["decisions"]["added"].get<int>(), 0);
  EXPECT_EQ(never_added["decisions"]["added"].get<int>(), 0);
  EXPECT_EQ(never_added["raw"], by_default["raw"]);
  EXPECT_EQ(never_added["frames"], by_default["frames"]);
}

// A field of the simulated segmenter set by name reaches the segmenter: without false
// positives and with no region bleeding outward, the raw masks paint fewer pixels where
// the ground truth has none. The run names the override; a wrong one is refused.
TEST_F(RunCliTest, SegmenterOptionsReachTheSegmenter) {
  const auto false_pixels = [](const nlohmann::json& seg) {
    long long pixels = 0;
    for (const nlohmann::json& category : seg["raw"]["categories"]) pixels += category["fp_pixels"].get<long long>();
    return pixels;
  };
  const nlohmann::json by_default = RunLoopAndReadSegJson("", dir_ / "default");
  const nlohmann::json tidy = RunLoopAndReadSegJson(
      "--segmenter-option false_positives_per_frame=0 --segmenter-option bleed_prob=0", dir_ / "tidy");
  EXPECT_NE(last_.stdout_text.find("seed 2 [false_positives_per_frame=0, bleed_prob=0]"), std::string::npos)
      << last_.stdout_text;
  EXPECT_LT(false_pixels(tidy), false_pixels(by_default) / 2);
  EXPECT_EQ(tidy["segmenter"], "simulated:fcis-like[false_positives_per_frame=0,bleed_prob=0]");

  const fs::path sequence = kDataDir / "office_seg" / "pass1";
  const CommandOutput unknown = Run("run " + sequence.string() + " --segmenter fcis-like --segmenter-option " +
                                    "hole_size=3 -q --out " + (dir_ / "unknown").string());
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_NE(unknown.stderr_text.find("hole_size"), std::string::npos) << unknown.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "unknown"));
}

}  // namespace
