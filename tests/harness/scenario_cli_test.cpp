// `segslam scenario run` end to end on a tiny office (scenarios/test/office_small.yaml,
// 25 frames per pass at 320x240): the report files, JUnit XML, and an exit code that
// follows the thresholds; and an unknown metric refused before any work.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "tests/harness/cli_runner.h"

namespace {

namespace fs = std::filesystem;
using segslam::testing::CommandOutput;
using segslam::testing::LineCount;
using segslam::testing::ReadText;

const fs::path kSmallOffice = fs::path(SEGSLAM_SOURCE_DIR) / "scenarios" / "test" / "office_small.yaml";

class ScenarioCliTest : public segslam::testing::CliScratchTest {
 protected:
  ScenarioCliTest() : CliScratchTest("segslam_scenario_") {}

  // office_small.yaml with extra sections appended.
  fs::path WriteScenario(const std::string& name, const std::string& sections) {
    const fs::path file = dir_ / (name + ".yaml");
    std::ofstream(file) << ReadText(kSmallOffice) << sections;
    return file;
  }
};

int Count(const std::string& text, const std::string& what) {
  int count = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++count;
  return count;
}

TEST_F(ScenarioCliTest, UnknownMetricFailsBeforeAnyWork) {
  const fs::path scenario = WriteScenario("bad", "expect:\n  mutual.ate_rmse: {max: 0.05}\n");
  const CommandOutput result = Run("scenario run " + scenario.string() + " --cache " + (dir_ / "cache").string() +
                                   " --out " + (dir_ / "report").string() + " -q");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(LineCount(result.stderr_text), 1) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find(scenario.string() + ": expect: unknown metric 'mutual.ate_rmse'"), std::string::npos)
      << result.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "cache"));
  EXPECT_FALSE(fs::exists(dir_ / "report"));

  // A mode that the scenario never runs is as unknown as a metric.
  const fs::path other = WriteScenario("other", "bench: {modes: [plain, mutual]}\nexpect:\n  mask-moveable.ate_rmse_m: {max: 0.05}\n");
  const CommandOutput modes = Run("scenario run " + other.string() + " --cache " + (dir_ / "cache").string() + " -q");
  EXPECT_EQ(modes.exit_code, 1);
  EXPECT_NE(modes.stderr_text.find("mode 'mask-moveable' does not run"), std::string::npos) << modes.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "cache"));
}

// A run replaces the report in its --out folder; a folder of other files is no report
// and is refused before any work, its files kept.
TEST_F(ScenarioCliTest, OutFolderOfOtherFilesIsRefusedAndKept) {
  const fs::path victim = dir_ / "victim";
  fs::create_directories(victim / "runs");
  fs::create_directories(victim / "figures");
  std::ofstream(victim / "runs" / "important.txt") << "keep me\n";
  std::ofstream(victim / "figures" / "plot.png") << "not a segslam figure\n";
  const CommandOutput result = Run("scenario run " + kSmallOffice.string() + " --cache " + (dir_ / "cache").string() +
                                   " --out " + victim.string() + " -q");
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(LineCount(result.stderr_text), 1) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find(victim.string() + ": holds other files and no segslam scenario report"),
            std::string::npos)
      << result.stderr_text;
  EXPECT_EQ(ReadText(victim / "runs" / "important.txt"), "keep me\n");
  EXPECT_TRUE(fs::exists(victim / "figures" / "plot.png"));

  // The scenario's own folder, whose scenario.yaml the report would replace.
  const fs::path experiment = dir_ / "experiment";
  fs::create_directories(experiment);
  fs::copy_file(kSmallOffice, experiment / "scenario.yaml");
  const CommandOutput own = Run("scenario run " + (experiment / "scenario.yaml").string() + " --cache " +
                                (dir_ / "cache").string() + " --out " + experiment.string() + " -q");
  EXPECT_EQ(own.exit_code, 1);
  EXPECT_NE(own.stderr_text.find("holds other files and no segslam scenario report"), std::string::npos)
      << own.stderr_text;
  EXPECT_EQ(ReadText(experiment / "scenario.yaml"), ReadText(kSmallOffice));
  EXPECT_FALSE(fs::exists(dir_ / "cache"));
}

// --junit names the XML file to write: an empty folder there was removed and the file
// written in its place, a folder of files gave a raw filesystem message at the end. Both
// are refused before any work, the folder kept.
TEST_F(ScenarioCliTest, JunitPathThatIsAFolderIsRefusedAndKept) {
  for (const bool empty : {true, false}) {
    const fs::path folder = dir_ / (empty ? "empty" : "full");
    fs::create_directories(folder);
    if (!empty) std::ofstream(folder / "other.xml") << "<kept/>";
    const CommandOutput result =
        Run("scenario run " + kSmallOffice.string() + " --frames 3 --modes plain --repeats 1 -q --cache " +
            (dir_ / "cache").string() + " --out " + (dir_ / "report").string() + " --junit " + folder.string());
    EXPECT_EQ(result.exit_code, 1);
    EXPECT_EQ(LineCount(result.stderr_text), 1) << result.stderr_text;
    EXPECT_NE(result.stderr_text.find(folder.string() + ": is a folder; --junit takes the path of the JUnit XML file"),
              std::string::npos)
        << result.stderr_text;
    EXPECT_TRUE(fs::is_directory(folder));
    if (!empty) {
      EXPECT_EQ(ReadText(folder / "other.xml"), "<kept/>");
    }
  }
  EXPECT_FALSE(fs::exists(dir_ / "cache"));
  EXPECT_FALSE(fs::exists(dir_ / "report"));
}

// A cached dataset whose files changed since generation is not used as the scenario's:
// a depth image edited in place (its size kept) is found by its SHA-256 on the next
// process's first use, and the dataset is generated anew.
TEST_F(ScenarioCliTest, AlteredCachedDatasetIsGeneratedAnew) {
  const std::string common = " --frames 3 --modes plain --repeats 1 -q --cache " + (dir_ / "cache").string() +
                             " --out " + (dir_ / "report").string();
  const CommandOutput first = Run("scenario run " + kSmallOffice.string() + common);
  ASSERT_EQ(first.exit_code, 0) << first.stderr_text;
  fs::path depth;
  for (const auto& entry : fs::recursive_directory_iterator(dir_ / "cache")) {
    if (entry.path().parent_path().filename() == "depth" && entry.path().extension() == ".png") depth = entry.path();
  }
  ASSERT_FALSE(depth.empty());
  std::string bytes = ReadText(depth);
  bytes[bytes.size() / 2] ^= 0x5a;
  std::ofstream(depth, std::ios::binary) << bytes;

  const CommandOutput second = Run("scenario run " + kSmallOffice.string() + common);
  EXPECT_EQ(second.exit_code, 0) << second.stderr_text;
  EXPECT_NE(second.stdout_text.find("differs from its manifest.json in 1 file(s)"), std::string::npos)
      << second.stdout_text;
  EXPECT_NE(second.stdout_text.find("generating it anew"), std::string::npos) << second.stdout_text;
  EXPECT_NE(ReadText(depth), bytes);  // the generated file is back

  const CommandOutput third = Run("scenario run " + kSmallOffice.string() + common + " --verify");
  EXPECT_EQ(third.exit_code, 0) << third.stderr_text;
  EXPECT_NE(third.stdout_text.find("(cached; sizes and SHA-256s match its manifest.json"), std::string::npos)
      << third.stdout_text;
}

TEST_F(ScenarioCliTest, TinyRunWritesTheReportAndItsExitCodeFollowsTheThresholds) {
  const std::string cache = (dir_ / "cache").string();
  const std::string common = " --frames 25 --repeats 2 --modes plain,mutual -q --cache " + cache;

  const fs::path passing = WriteScenario("passing",
                                         "bench: {segmenter: fcis-like, seed: 4}\n"
                                         "expect:\n"
                                         "  plain.localized_share: {min: 0.5}\n"
                                         "  pass2.mutual.localized_share: {min: 0}\n"
                                         "  mutual_vs_plain.ate_ratio: {max: 1000}\n");
  const fs::path report = dir_ / "report";
  const fs::path junit = dir_ / "junit.xml";
  const CommandOutput pass = Run("scenario run " + passing.string() + common + " --out " + report.string() +
                                 " --junit " + junit.string());
  std::printf("%s", pass.stdout_text.c_str());
  ASSERT_EQ(pass.exit_code, 0) << pass.stdout_text << pass.stderr_text;
  EXPECT_NE(pass.stdout_text.find("3 of 3 expectations passed"), std::string::npos);
  for (const char* file : {"results.json", "report.md", "report.html", "figures/trajectories_pass1.png",
                           "figures/trajectories_pass2.png", "figures/error_pass1.png", "figures/error_pass2.png",
                           "figures/masks_raw_vs_refined.png", "figures/features_kept_vs_dropped.png"}) {
    EXPECT_TRUE(fs::exists(report / file)) << file;
  }
  EXPECT_EQ(pass.stdout_text.find("figure not drawn"), std::string::npos) << pass.stdout_text;

  const nlohmann::json results = nlohmann::json::parse(ReadText(report / "results.json"));
  EXPECT_EQ(results["scenario"], "office_small");
  EXPECT_EQ(results["passed"], true);
  EXPECT_FALSE(results["code_version"].get<std::string>().empty());
  EXPECT_GT(results["machine"]["cores"].get<int>(), 0);
  EXPECT_EQ(results["dataset_movers_left_out"], 0);  // the small office's two people have room
  EXPECT_EQ(results["dataset_red_lights_left_out"], 0);
  // plain is deterministic: one run; mutual: two seeds.
  ASSERT_EQ(results["runs"].size(), 3u);
  EXPECT_EQ(results["runs"][1]["seed"], 4);
  EXPECT_EQ(results["runs"][2]["seed"], 5);
  EXPECT_EQ(results["summary"]["pass1"]["mutual"]["ate_rmse_m"]["count"], 2);
  EXPECT_EQ(results["runs"][2]["evaluation"]["passes"][0]["frames"], 25);
  // Every tunable as the runs used it, not only the bench: section's overrides.
  EXPECT_EQ(results["options"]["tracker"]["orb.max_features"], 1000);
  EXPECT_GT(results["options"]["tracker"].size(), 50u);
  EXPECT_EQ(results["options"]["refiner"]["depth_tolerance"], 0.05);
  const std::string markdown = ReadText(report / "report.md");
  EXPECT_NE(markdown.find("Effective options"), std::string::npos);
  EXPECT_NE(markdown.find("pose\\_optimizer.rounds"), std::string::npos) << "the whole list, escaped for markdown";
  EXPECT_NE(markdown.find("per sequence and mode (as the paper's Table I)"), std::string::npos);
  EXPECT_NE(markdown.find("Relocalization in pass 2"), std::string::npos);
  EXPECT_NE(markdown.find("raw vs refined"), std::string::npos);
  for (const char* figure : {"figures/trajectories_pass2.png", "figures/error_pass2.png",
                             "figures/masks_raw_vs_refined.png", "figures/features_kept_vs_dropped.png"}) {
    EXPECT_NE(markdown.find(figure), std::string::npos) << figure;
    EXPECT_NE(ReadText(report / "report.html").find(figure), std::string::npos) << figure;
  }
  const std::string xml = ReadText(junit);
  EXPECT_EQ(Count(xml, "<testcase "), 3) << xml;
  EXPECT_EQ(Count(xml, "<failure"), 0) << xml;

  // The thresholds are no part of the dataset: the second run reuses it and fails. It
  // runs three at a time, with the same results as one at a time.
  const fs::path failing = WriteScenario("failing",
                                         "bench: {segmenter: fcis-like, seed: 4}\n"
                                         "expect:\n"
                                         "  mutual.ate_rmse_m: {max: 0.0000001}\n"
                                         "  plain.localized_share: {min: 0.5}\n");
  const CommandOutput fail = Run("scenario run " + failing.string() + common + " --jobs 3 --out " +
                                 (dir_ / "report2").string() + " --junit " + junit.string());
  std::printf("%s", fail.stdout_text.c_str());
  EXPECT_EQ(fail.exit_code, 2) << fail.stderr_text;
  EXPECT_NE(fail.stdout_text.find("(cached; sizes and SHA-256s match its manifest.json"), std::string::npos);
  EXPECT_NE(fail.stdout_text.find("FAIL  mutual.ate_rmse_m"), std::string::npos);
  EXPECT_NE(fail.stdout_text.find("1 of 2 expectations passed"), std::string::npos);
  const nlohmann::json parallel = nlohmann::json::parse(ReadText(dir_ / "report2" / "results.json"));
  ASSERT_EQ(parallel["runs"].size(), results["runs"].size());
  for (std::size_t r = 0; r < results["runs"].size(); ++r) {
    EXPECT_EQ(parallel["runs"][r]["seed"], results["runs"][r]["seed"]);
    for (std::size_t p = 0; p < 2; ++p) {
      for (const char* key : {"ate", "rpe", "localized_frames", "moving_detection", "segmentation"}) {
        EXPECT_EQ(parallel["runs"][r]["evaluation"]["passes"][p][key], results["runs"][r]["evaluation"]["passes"][p][key])
            << "run " << r << " pass " << p + 1 << " " << key;
      }
    }
  }
  const std::string failed_xml = ReadText(junit);
  EXPECT_EQ(Count(failed_xml, "<testcase "), 2) << failed_xml;
  EXPECT_EQ(Count(failed_xml, "<failure"), 1) << failed_xml;

  // --modes leaving mutual out: its threshold is not checked (and says so), the rest is.
  const CommandOutput narrowed = Run("scenario run " + failing.string() + " --frames 25 --modes plain -q --cache " +
                                     cache + " --out " + (dir_ / "report3").string());
  EXPECT_EQ(narrowed.exit_code, 0) << narrowed.stdout_text << narrowed.stderr_text;
  EXPECT_NE(narrowed.stdout_text.find("expectation mutual.ate_rmse_m not checked"), std::string::npos)
      << narrowed.stdout_text;
  EXPECT_NE(narrowed.stdout_text.find("1 of 1 expectations passed"), std::string::npos) << narrowed.stdout_text;
  // Without the mutual mode Figs. 5 and 6 cannot be drawn: said, not fatal, not shown.
  EXPECT_NE(narrowed.stdout_text.find("figure not drawn: figures/masks_raw_vs_refined.png"), std::string::npos)
      << narrowed.stdout_text;
  EXPECT_NE(narrowed.stdout_text.find("figure not drawn: figures/features_kept_vs_dropped.png"), std::string::npos)
      << narrowed.stdout_text;
  EXPECT_EQ(ReadText(dir_ / "report3" / "report.md").find("features_kept_vs_dropped"), std::string::npos);

  // --modes leaving every threshold out checked nothing: not a pass, and JUnit says so.
  const fs::path skipped_junit = dir_ / "skipped.xml";
  const CommandOutput none = Run("scenario run " + failing.string() + " --frames 25 --modes mask-moveable -q --cache " +
                                 cache + " --out " + (dir_ / "report4").string() + " --junit " + skipped_junit.string());
  EXPECT_EQ(none.exit_code, 2) << none.stdout_text << none.stderr_text;
  EXPECT_NE(none.stdout_text.find("0 of 0 expectations passed, 2 not checked"), std::string::npos) << none.stdout_text;
  EXPECT_NE(none.stdout_text.find("no expectation was checked"), std::string::npos) << none.stdout_text;
  const std::string skipped_xml = ReadText(skipped_junit);
  EXPECT_EQ(Count(skipped_xml, "<skipped "), 2) << skipped_xml;
  EXPECT_EQ(nlohmann::json::parse(ReadText(dir_ / "report4" / "results.json"))["passed"], false);

  // Beside the dataset, a record of the build that generated it. prune-cache keeps this
  // build's dataset and removes another build's (listing it first with --dry-run).
  std::vector<fs::path> records;
  for (const auto& entry : fs::directory_iterator(cache)) {
    if (entry.path().extension() == ".json") records.push_back(entry.path());
  }
  ASSERT_EQ(records.size(), 1u);
  const fs::path dataset = records[0].parent_path() / records[0].stem();
  EXPECT_TRUE(fs::is_directory(dataset / "pass1")) << dataset;
  EXPECT_EQ(nlohmann::json::parse(ReadText(records[0]))["code_version"], results["code_version"]);
  const fs::path other_build = fs::path(cache) / "office_small-aaaaaaaaaaaa";
  fs::create_directories(other_build);
  fs::copy(dataset / "manifest.json", other_build / "manifest.json");
  std::ofstream(fs::path(cache) / "office_small-aaaaaaaaaaaa.json") << R"({"code_version": "v0.1-old"})";
  const CommandOutput dry = Run("scenario prune-cache --dry-run --cache " + cache);
  EXPECT_EQ(dry.exit_code, 0) << dry.stderr_text;
  EXPECT_NE(dry.stdout_text.find("v0.1-old"), std::string::npos) << dry.stdout_text;
  EXPECT_NE(dry.stdout_text.find("would remove 1 dataset(s)"), std::string::npos) << dry.stdout_text;
  EXPECT_TRUE(fs::exists(other_build));
  const CommandOutput pruned = Run("scenario prune-cache --cache " + cache);
  EXPECT_EQ(pruned.exit_code, 0) << pruned.stderr_text;
  EXPECT_NE(pruned.stdout_text.find("kept (this build)"), std::string::npos) << pruned.stdout_text;
  EXPECT_FALSE(fs::exists(other_build));
  EXPECT_FALSE(fs::exists(fs::path(cache) / "office_small-aaaaaaaaaaaa.json"));
  EXPECT_TRUE(fs::exists(dataset / "manifest.json"));
  EXPECT_TRUE(fs::exists(records[0]));
}

// With bench.static_twin, plain also runs on the same office without its walkers, and
// each mode's share of the walkers' added error it removes is reported, usable in
// expect:; its value is (plain - mode) / (plain - plain on the twin) of the medians.
TEST_F(ScenarioCliTest, StaticTwinGivesEachModesShareOfTheTrafficsErrorRemoved) {
  const fs::path scenario = WriteScenario("twin",
                                          "bench: {segmenter: gt, static_twin: true}\n"
                                          "expect:\n"
                                          "  pass2.mutual.traffic_error_removed: {min: -1000}\n");
  const fs::path report = dir_ / "report";
  const CommandOutput result = Run("scenario run " + scenario.string() + " --frames 25 --modes plain,mutual -q --cache " +
                                   (dir_ / "cache").string() + " --out " + report.string());
  const nlohmann::json results = nlohmann::json::parse(ReadText(report / "results.json"));
  // The expectation holds where the walkers added error to plain; without, it has no
  // value and fails (exit code 2).
  const bool added = !results["static_twin"]["traffic_error_removed"]["pass2"]["mutual"].is_null();
  EXPECT_EQ(result.exit_code, added ? 0 : 2) << result.stdout_text << result.stderr_text;
  EXPECT_EQ(results["bench"]["static_twin"], true);
  const nlohmann::json& twin = results["static_twin"];
  EXPECT_NE(twin["dataset"].get<std::string>().find("office_small_static_twin-"), std::string::npos);
  ASSERT_EQ(twin["runs"].size(), 1u);
  EXPECT_EQ(twin["runs"][0]["mode"], "plain");
  EXPECT_TRUE(fs::exists(report / twin["runs"][0]["run_dir"].get<std::string>() / "pass1" / "trajectory.txt"));
  for (const char* pass : {"pass1", "pass2"}) {
    SCOPED_TRACE(pass);
    const nlohmann::json& summary = results["summary"][pass];
    const double plain = summary["plain"]["ate_rmse_m"]["median"];
    const double mutual = summary["mutual"]["ate_rmse_m"]["median"];
    const double still = summary["plain-static-twin"]["ate_rmse_m"]["median"];
    EXPECT_EQ(summary["plain-static-twin"]["ate_rmse_m"]["runs"], 1);
    const nlohmann::json& removed = twin["traffic_error_removed"][pass];
    if (plain > still) {
      EXPECT_NEAR(removed["mutual"].get<double>(), (plain - mutual) / (plain - still), 1e-9);
      EXPECT_EQ(removed["plain"].get<double>(), 0.0);
    } else {
      EXPECT_TRUE(removed["mutual"].is_null()) << "no added error to remove";
    }
  }
  EXPECT_NE(ReadText(report / "report.md").find("The static twin"), std::string::npos);

  // Without the twin there is nothing to measure against: refused before any work.
  const fs::path without = WriteScenario("no_twin",
                                         "bench: {segmenter: gt}\n"
                                         "expect:\n"
                                         "  pass2.mutual.traffic_error_removed: {min: 0.5}\n");
  const CommandOutput refused = Run("scenario run " + without.string() + " --frames 3 -q --cache " +
                                    (dir_ / "cache2").string() + " --out " + (dir_ / "report2").string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.stderr_text.find("needs the static twin (bench: {static_twin: true}"), std::string::npos)
      << refused.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "cache2"));
}

// With bench.feature_jitter, plain, the oracle and the static twin run every repeat too,
// each with its repeat's feature budget, and the medians are over those runs.
TEST_F(ScenarioCliTest, FeatureJitterRepeatsEveryModeAndTheTwinWithTheirBudgets) {
  const fs::path scenario = WriteScenario("jitter", "bench: {segmenter: gt, static_twin: true, feature_jitter: 50}\n");
  const fs::path report = dir_ / "report";
  const CommandOutput result = Run("scenario run " + scenario.string() +
                                   " --frames 12 --modes plain,oracle --repeats 3 -q --cache " +
                                   (dir_ / "cache").string() + " --out " + report.string());
  ASSERT_EQ(result.exit_code, 0) << result.stdout_text << result.stderr_text;
  const nlohmann::json results = nlohmann::json::parse(ReadText(report / "results.json"));
  EXPECT_EQ(results["bench"]["feature_jitter"], 50);
  const std::vector<int> budgets = {1000, 1050, 950};
  for (const char* mode : {"plain", "oracle"}) {
    SCOPED_TRACE(mode);
    std::vector<int> seen;
    std::vector<std::string> dirs;
    for (const nlohmann::json& run : results["runs"]) {
      if (run["mode"] != mode) continue;
      seen.push_back(run["orb_max_features"]);
      dirs.push_back(run["run_dir"]);
      EXPECT_TRUE(fs::exists(report / run["run_dir"].get<std::string>() / "pass2" / "trajectory.txt"));
    }
    EXPECT_EQ(seen, budgets);
    EXPECT_EQ(std::set<std::string>(dirs.begin(), dirs.end()).size(), 3u);
    EXPECT_EQ(results["summary"]["pass1"][mode]["ate_rmse_m"]["runs"], 3);
  }
  const nlohmann::json& twin_runs = results["static_twin"]["runs"];
  ASSERT_EQ(twin_runs.size(), 3u);
  for (std::size_t r = 0; r < 3; ++r) EXPECT_EQ(twin_runs[r]["orb_max_features"], budgets[r]);
  EXPECT_EQ(results["summary"]["pass1"]["plain-static-twin"]["ate_rmse_m"]["runs"], 3);
  // The budget reaches the tracker: each run records the options it ran with.
  const nlohmann::json last_plain =
      nlohmann::json::parse(ReadText(report / results["runs"][2]["run_dir"].get<std::string>() / "run.json"));
  ASSERT_EQ(results["runs"][2]["mode"], "plain");
  EXPECT_EQ(last_plain["options"]["tracker"]["orb.max_features"], 950);
}

}  // namespace
