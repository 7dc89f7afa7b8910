// `segslam bench aliasing` on a generated dataset (fixture sim_datasets) and on one of
// its sequences, and the summary `segslam generate` records in manifest.json. What the
// measure finds is tested in aliasing_test.cpp; here the command's table, JSON, picture,
// determinism and errors.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <string>

#include "core/manifest.h"
#include "tests/harness/cli_runner.h"

namespace {

namespace fs = std::filesystem;
using segslam::testing::CommandOutput;
using segslam::testing::ReadText;

const fs::path kDataDir = SEGSLAM_TEST_DATA_DIR;

// The table without the "worst pair drawn in FILE" lines of --pictures.
std::string WithoutPictureLines(const std::string& text) {
  std::string kept;
  size_t start = 0;
  while (start < text.size()) {
    const size_t end = std::min(text.find('\n', start), text.size() - 1);
    const std::string line = text.substr(start, end + 1 - start);
    if (line.find("worst pair drawn in") == std::string::npos) kept += line;
    start = end + 1;
  }
  return kept;
}

class AliasingCliTest : public segslam::testing::CliScratchTest {
 protected:
  AliasingCliTest() : CliScratchTest("segslam_aliasing_cli_") {}
};

TEST_F(AliasingCliTest, ReportsEachPassTheSameWayEveryTime) {
  const fs::path dataset = kDataDir / "city_static";
  ASSERT_TRUE(fs::is_directory(dataset / "pass2")) << dataset;
  const fs::path json_file = dir_ / "aliasing.json";
  const fs::path pictures = dir_ / "pictures";
  // A straight street shares some view between all its frames; counting pairs that share
  // less than 90 % as "no common view" gives the matcher pairs with much to verify.
  const std::string command = "bench aliasing " + dataset.string() + " --spacing 2 --min-common-share 0.9 --json " +
                              json_file.string();
  const CommandOutput out = Run(command + " --pictures " + pictures.string());
  ASSERT_EQ(out.exit_code, 0) << out.stderr_text;
  for (const char* row : {"\npass1 ", "\npass2 ", "p50", "p90", "p99", ">=20"}) {
    EXPECT_NE(out.stdout_text.find(row), std::string::npos) << row << " missing from:\n" << out.stdout_text;
  }
  const nlohmann::json json = nlohmann::json::parse(ReadText(json_file));
  EXPECT_EQ(json.at("settings").at("sample_spacing_m"), 2.0);
  EXPECT_EQ(json.at("settings").at("min_common_share"), 0.9);
  EXPECT_EQ(json.at("settings").at("ratio").get<double>(), 0.8f);
  for (const char* pass : {"pass1", "pass2"}) {
    SCOPED_TRACE(pass);
    const nlohmann::json& p = json.at("passes").at(pass);
    EXPECT_EQ(p.at("frames"), 120);
    const int sampled = p.at("sampled_frames");
    EXPECT_GE(sampled, 5) << "the route runs more than 10 m";
    EXPECT_EQ(p.at("pairs_tested"), sampled * (sampled - 1) / 2);
    EXPECT_GT(p.at("pairs_no_common_view").get<int>(), 0);
    EXPECT_LE(p.at("pairs_no_common_view").get<int>(), p.at("pairs_tested").get<int>());
    EXPECT_LE(p.at("p50").get<int>(), p.at("p90").get<int>());
    EXPECT_LE(p.at("p99").get<int>(), p.at("max_verified_matches").get<int>());
    const nlohmann::json& worst = p.at("worst_pairs");
    ASSERT_FALSE(worst.empty());
    EXPECT_EQ(worst[0].at("verified_matches"), p.at("max_verified_matches"));
    EXPECT_LT(worst[0].at("frame_a").get<int>(), worst[0].at("frame_b").get<int>());
    EXPECT_LT(worst[0].at("common_share").get<double>(), 0.9);
    EXPECT_GE(p.at("max_verified_matches").get<int>(), 20) << "neighbours 2 m apart on one street";
    EXPECT_GE(worst[0].at("pose_error_m").get<double>(), 0.0) << "a pose was found";
    EXPECT_TRUE(fs::exists(pictures / (std::string(pass) + "_worst_pair.png")));
  }
  // Same input, same bytes: the table and the JSON, with one thread as with all.
  const std::string first_json = ReadText(json_file);
  const CommandOutput again = Run(command + " --threads 1");
  ASSERT_EQ(again.exit_code, 0) << again.stderr_text;
  EXPECT_EQ(ReadText(json_file), first_json);
  EXPECT_EQ(WithoutPictureLines(again.stdout_text), WithoutPictureLines(out.stdout_text));
}

TEST_F(AliasingCliTest, MeasuresOneSequenceAndNeedsItsGroundTruth) {
  const fs::path source = kDataDir / "office_static" / "pass1";
  ASSERT_TRUE(fs::is_directory(source)) << source;
  const CommandOutput out = Run("bench aliasing " + source.string());
  ASSERT_EQ(out.exit_code, 0) << out.stderr_text;
  EXPECT_NE(out.stdout_text.find("\npass1 "), std::string::npos) << "named after its folder:\n" << out.stdout_text;

  const fs::path copy = dir_ / "sequence";
  fs::copy(source, copy, fs::copy_options::recursive);
  fs::remove(copy / "groundtruth.txt");
  const CommandOutput refused = Run("bench aliasing " + copy.string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.stderr_text.find((copy / "groundtruth.txt").string()), std::string::npos) << refused.stderr_text;

  const CommandOutput bad = Run("bench aliasing " + source.string() + " --min-common-share 2");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.stderr_text.find("min-common-share"), std::string::npos) << bad.stderr_text;
}

// generate measures both passes before the dataset is renamed into place: the summary is
// in manifest.json's extra, and every checksum still holds.
TEST_F(AliasingCliTest, GenerateRecordsTheSummaryInTheManifest) {
  const std::string scenario = std::string(SEGSLAM_SOURCE_DIR) + "/scenarios/test/office_small.yaml";
  const fs::path out_dir = dir_ / "office";
  const CommandOutput out = Run("generate " + scenario + " --out " + out_dir.string() + " --frames 12 -q");
  ASSERT_EQ(out.exit_code, 0) << out.stderr_text;
  EXPECT_NE(out.stdout_text.find("extra.aliasing"), std::string::npos) << out.stdout_text;
  EXPECT_TRUE(segslam::VerifyManifest(out_dir).empty());
  const nlohmann::json extra = nlohmann::json::parse(ReadText(out_dir / "manifest.json")).at("extra");
  const nlohmann::json& aliasing = extra.at("aliasing");
  EXPECT_EQ(aliasing.at("settings").at("sample_spacing_m"), 4.0);
  for (const char* pass : {"pass1", "pass2"}) {
    SCOPED_TRACE(pass);
    const nlohmann::json& p = aliasing.at("passes").at(pass);
    EXPECT_GE(p.at("sampled_frames").get<int>(), 1);
    EXPECT_GE(p.at("max_verified_matches").get<int>(), 0);
    EXPECT_GE(p.at("pairs_at_or_above_20").get<int>(), 0);
  }

  const fs::path plain_dir = dir_ / "plain";
  const CommandOutput plain =
      Run("generate " + scenario + " --out " + plain_dir.string() + " --frames 12 -q --no-aliasing");
  ASSERT_EQ(plain.exit_code, 0) << plain.stderr_text;
  EXPECT_FALSE(nlohmann::json::parse(ReadText(plain_dir / "manifest.json")).at("extra").contains("aliasing"));
  // The passes themselves are the same bytes with and without the measure.
  EXPECT_EQ(ReadText(out_dir / "pass1" / "manifest.json"), ReadText(plain_dir / "pass1" / "manifest.json"));
}

}  // namespace
