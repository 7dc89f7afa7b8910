// `segslam eval-traj` end to end on TUM's fr1/xyz RGBDSLAM example: the table and the
// JSON carry the numbers TUM's scripts print (shared/data/tum_fr1_xyz_trajectories/
// SOURCE.md; skipped where a clone has no ../shared/data), and bad input gets one line on
// stderr naming the file.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/harness/cli_runner.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using segslam::testing::CommandOutput;
using segslam::testing::ReadText;

const std::string kTumDir = SEGSLAM_SHARED_DATA_DIR "/tum_fr1_xyz_trajectories";

class EvalTrajCliTest : public segslam::testing::CliScratchTest {
 protected:
  EvalTrajCliTest() : CliScratchTest("segslam_eval_traj_") {}
};

// The whitespace-separated fields of the table row that starts with `metric`.
std::vector<std::string> RowFields(const std::string& table, const std::string& metric) {
  std::istringstream lines(table);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(metric, 0) != 0) continue;
    std::istringstream fields(line.substr(metric.size()));
    std::vector<std::string> result;
    for (std::string field; fields >> field;) result.push_back(field);
    return result;
  }
  ADD_FAILURE() << "no row '" << metric << "' in:\n" << table;
  return {};
}

TEST_F(EvalTrajCliTest, ReproducesTumScriptsOnFr1Xyz) {
  if (!fs::exists(kTumDir)) GTEST_SKIP() << kTumDir << " not present";
  const fs::path json_file = dir_ / "eval.json";
  const CommandOutput result =
      Run("eval-traj " + kTumDir + "/groundtruth.txt " + kTumDir +
                 "/rgbdslam_estimate.txt --json " + json_file.string());
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;

  // pairs, rmse, mean, median, std, min, max
  EXPECT_EQ(RowFields(result.stdout_text, "ATE translation [m]"),
            (std::vector<std::string>{"786", "0.013473", "0.012029", "0.011176", "0.006068",
                                      "0.000939", "0.034727"}));
  const std::vector<std::string> rpe_translation =
      RowFields(result.stdout_text, "RPE translation [m]");
  ASSERT_EQ(rpe_translation.size(), 7u);
  EXPECT_EQ(rpe_translation[0], "753");
  EXPECT_EQ(rpe_translation[1], "0.021217");
  EXPECT_EQ(rpe_translation[2], "0.019524");
  const std::vector<std::string> rpe_rotation = RowFields(result.stdout_text, "RPE rotation [deg]");
  ASSERT_EQ(rpe_rotation.size(), 7u);
  EXPECT_EQ(rpe_rotation[1], "0.934480");
  EXPECT_EQ(rpe_rotation[2], "0.841472");

  const nlohmann::json json = nlohmann::json::parse(ReadText(json_file));
  EXPECT_EQ(json["ate"]["translation_m"]["count"], 786);
  EXPECT_NEAR(json["ate"]["translation_m"]["rmse"].get<double>(), 0.013473, 5e-7);
  EXPECT_EQ(json["ate"]["aligned"], true);
  EXPECT_EQ(json["rpe"]["translation_m"]["count"], 753);
  EXPECT_NEAR(json["rpe"]["rotation_deg"]["rmse"].get<double>(), 0.934480, 5e-7);
  // Nothing but the JSON itself is left in the directory (no temporary file).
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(EvalTrajCliTest, RpeInFrames) {
  if (!fs::exists(kTumDir)) GTEST_SKIP() << kTumDir << " not present";
  const CommandOutput result =
      Run("eval-traj " + kTumDir + "/groundtruth.txt " + kTumDir +
                 "/rgbdslam_estimate.txt --rpe-delta 1 --rpe-unit f");
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  const std::vector<std::string> translation = RowFields(result.stdout_text, "RPE translation [m]");
  const std::vector<std::string> rotation = RowFields(result.stdout_text, "RPE rotation [deg]");
  ASSERT_EQ(translation.size(), 7u);
  ASSERT_EQ(rotation.size(), 7u);
  EXPECT_EQ(translation[0], "783");
  EXPECT_EQ(translation[1], "0.005763");
  EXPECT_EQ(rotation[1], "0.352969");
}

TEST_F(EvalTrajCliTest, MissingFileIsOneLineNamingIt) {
  const fs::path json_file = dir_ / "eval.json";
  const std::string missing = (dir_ / "no_such_estimate.txt").string();
  const fs::path ground_truth = dir_ / "groundtruth.txt";
  std::ofstream(ground_truth) << "# timestamp tx ty tz qx qy qz qw\n"
                                 "100.0 0 0 0 0 0 0 1\n100.1 0.1 0 0 0 0 0 1\n100.2 0.2 0 0 0 0 0 1\n";
  const CommandOutput result = Run("eval-traj " + ground_truth.string() + " " + missing +
                                          " --json " + json_file.string());
  EXPECT_NE(result.exit_code, 0);
  EXPECT_EQ(std::count(result.stderr_text.begin(), result.stderr_text.end(), '\n'), 1)
      << result.stderr_text;
  EXPECT_NE(result.stderr_text.find(missing), std::string::npos) << result.stderr_text;
  EXPECT_FALSE(fs::exists(json_file));
}

TEST_F(EvalTrajCliTest, UnknownRpeUnitIsRefused) {
  const CommandOutput result = Run("eval-traj " + kTumDir + "/groundtruth.txt " + kTumDir +
                                          "/rgbdslam_estimate.txt --rpe-unit m");
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.stderr_text.find("rpe-unit"), std::string::npos) << result.stderr_text;
}

}  // namespace
