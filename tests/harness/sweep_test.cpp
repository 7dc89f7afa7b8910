// The sweep's grid, sweep files, shards and merge (harness/sweep.h), and `segslam sweep`
// end to end on a tiny office: two shards merged give the same table as one run, a sweep
// file over the segmenter's error strength, and bad input is one line.
#include "harness/sweep.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include "core/error.h"
#include "harness/scenario_runner.h"
#include "scenes/scenario.h"
#include "tests/harness/cli_runner.h"

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;
using segslam::testing::CommandOutput;
using segslam::testing::LineCount;
using segslam::testing::ReadText;

TEST(SweepGridTest, ListsBecomeAxesAndSingleValuesFixedOverrides) {
  const SweepGrid grid = SweepGrid::FromSetOptions(
      {"city.moving_cars=0,4,8", "city.pedestrians=10", "pass2.camera_offset_m=[0,0.5,0]", "city.crossing_share=0.1,0.5"});
  ASSERT_EQ(grid.axes.size(), 2u);
  EXPECT_EQ(grid.axes[0].key, "city.moving_cars");
  EXPECT_EQ(grid.axes[0].values, (std::vector<std::string>{"0", "4", "8"}));
  EXPECT_EQ(grid.fixed_overrides,
            (std::vector<std::string>{"city.pedestrians=10", "pass2.camera_offset_m=[0,0.5,0]"}));
  ASSERT_EQ(grid.PointCount(), 6);
  // The first axis varies slowest.
  EXPECT_EQ(grid.PointAssignments(0), (std::vector<std::string>{"city.moving_cars=0", "city.crossing_share=0.1"}));
  EXPECT_EQ(grid.PointAssignments(1), (std::vector<std::string>{"city.moving_cars=0", "city.crossing_share=0.5"}));
  EXPECT_EQ(grid.PointAssignments(5), (std::vector<std::string>{"city.moving_cars=8", "city.crossing_share=0.5"}));
  EXPECT_EQ(grid.PointName(5), "city.moving_cars=8__city.crossing_share=0.5");
  std::set<std::string> names;
  for (int p = 0; p < grid.PointCount(); ++p) names.insert(grid.PointName(p));
  EXPECT_EQ(names.size(), 6u);
  // The grid survives its JSON form.
  const SweepGrid again = SweepGrid::FromJson(grid.ToJson(), "test");
  EXPECT_EQ(again.ToJson(), grid.ToJson());
}

// Plots put numeric axes at their values, ascending whichever way the sweep lists them,
// and anything else (words, duplicates) at 0, 1, 2, ... in the listed order.
TEST(SweepGridTest, AxisValuesArePlacedOnThePlotInAscendingOrder) {
  const AxisPlacement far_to_near = PlaceAxisOnPlot({"office.walker_front_distance_m", {"1.15", "0.85", "0.5"}});
  EXPECT_TRUE(far_to_near.numeric);
  EXPECT_EQ(far_to_near.x, (std::vector<double>{0.5, 0.85, 1.15}));
  EXPECT_EQ(far_to_near.value_index, (std::vector<std::size_t>{2, 1, 0}));
  const AxisPlacement ascending = PlaceAxisOnPlot({"city.moving_cars", {"0", "4", "16"}});
  EXPECT_EQ(ascending.x, (std::vector<double>{0, 4, 16}));
  EXPECT_EQ(ascending.value_index, (std::vector<std::size_t>{0, 1, 2}));
  for (const SweepAxis& axis : {SweepAxis{"office.camera_motion", {"xyz", "static", "rpy"}},
                                SweepAxis{"city.moving_cars", {"4", "0", "4"}},
                                SweepAxis{"pass2.camera_offset_m", {"[0,0.5,0]", "[0,1,0]", "2m"}}}) {
    const AxisPlacement placed = PlaceAxisOnPlot(axis);
    EXPECT_FALSE(placed.numeric) << axis.key;
    EXPECT_EQ(placed.x, (std::vector<double>{0, 1, 2})) << axis.key;
    EXPECT_EQ(placed.value_index, (std::vector<std::size_t>{0, 1, 2})) << axis.key;
  }
}

TEST(SweepGridTest, MalformedSetIsAnErrorNamingIt) {
  EXPECT_THROW(SweepGrid::FromSetOptions({"city.moving_cars"}), Error);
  EXPECT_THROW(SweepGrid::FromSetOptions({"city.moving_cars="}), Error);
  EXPECT_THROW(SweepGrid::FromSetOptions({"city.moving_cars=0,,8"}), Error);
  try {
    SweepGrid::FromSetOptions({"=4"});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("sweep --set =4"), std::string::npos) << e.what();
  }
}

TEST(SweepGridTest, SetOptionsLayOverAGrid) {
  SweepGrid grid;
  grid.axes = {{"city.moving_cars", {"0", "8"}}, {"city.pedestrians", {"0", "20"}}};
  grid.fixed_overrides = {"bench.repeats=3"};
  const SweepGrid laid = grid.WithSetOptions(
      {"city.moving_cars=0,4,8,16", "city.pedestrians=10", "bench.repeats=1", "city.crossing_share=0.1,0.5"});
  // A list replaces the key's axis in place, or adds an axis at the end.
  ASSERT_EQ(laid.axes.size(), 2u);
  EXPECT_EQ(laid.axes[0].key, "city.moving_cars");
  EXPECT_EQ(laid.axes[0].values, (std::vector<std::string>{"0", "4", "8", "16"}));
  EXPECT_EQ(laid.axes[1].key, "city.crossing_share");
  // One value fixes the key (its axis goes) and comes after the file's, so it wins.
  EXPECT_EQ(laid.fixed_overrides,
            (std::vector<std::string>{"bench.repeats=3", "city.pedestrians=10", "bench.repeats=1"}));
  EXPECT_EQ(laid.PointCount(), 8);
  EXPECT_THROW(grid.WithSetOptions({"city.moving_cars"}), Error);
}

class SweepFileTest : public segslam::testing::CliScratchTest {
 protected:
  SweepFileTest() : CliScratchTest("segslam_sweep_file_") {}

  fs::path Write(const std::string& name, const std::string& text) {
    const fs::path file = dir_ / name;
    std::ofstream(file) << text;
    return file;
  }
};

TEST_F(SweepFileTest, LoadsScenarioFixedKeysAndAxes) {
  fs::create_directories(dir_ / "scenarios" / "sweeps");
  std::ofstream(dir_ / "scenarios" / "base.yaml") << "kind: office\n";
  const fs::path file = Write("scenarios/sweeps/study.yaml",
                              "scenario: ../base.yaml\nset: [bench.repeats=2, seed=5]\naxes:\n"
                              "  office.people_walking: [0, 2, 4]\n"
                              "  pass2.camera_offset_m: [[0, 0.2, 0], [0, 0.5, 0]]\n");
  ASSERT_TRUE(SweepFile::Recognize(file));
  EXPECT_FALSE(SweepFile::Recognize(dir_ / "scenarios" / "base.yaml"));
  const SweepFile sweep = SweepFile::Load(file);
  EXPECT_EQ(sweep.name, "study");  // the file's stem without name:
  EXPECT_EQ(sweep.scenario, dir_ / "scenarios" / "base.yaml");
  EXPECT_EQ(sweep.grid.fixed_overrides, (std::vector<std::string>{"bench.repeats=2", "seed=5"}));
  ASSERT_EQ(sweep.grid.axes.size(), 2u);
  EXPECT_EQ(sweep.grid.axes[0].key, "office.people_walking");
  EXPECT_EQ(sweep.grid.axes[0].values, (std::vector<std::string>{"0", "2", "4"}));
  // A list value is one value, spelt as --set would take it; it applies as a vector.
  EXPECT_EQ(sweep.grid.axes[1].values, (std::vector<std::string>{"[0, 0.2, 0]", "[0, 0.5, 0]"}));
  scenes::Scenario scenario = scenes::LoadScenario(sweep.scenario);
  scenes::ApplyOverride(scenario, "pass2.camera_offset_m", sweep.grid.axes[1].values[1]);
  EXPECT_DOUBLE_EQ(scenario.pass2.camera_offset_m.y(), 0.5);
}

TEST_F(SweepFileTest, BadFilesAreRefusedNamingFileAndKey) {
  std::ofstream(dir_ / "base.yaml") << "kind: office\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"scenario: base.yaml\naxes: {office.people_walking: [0, 2]}\nrepeats: 3\n", "unknown key 'repeats'"},
      {"axes: {office.people_walking: [0, 2]}\n", "scenario:"},
      {"scenario: nowhere.yaml\naxes: {office.people_walking: [0, 2]}\n", "nowhere.yaml: no such file"},
      {"scenario: base.yaml\naxes: {office.people_walking: [2]}\n", "office.people_walking: expected a list of at least two"},
      {"scenario: base.yaml\naxes: {office.people_walking: 2}\n", "office.people_walking: expected a list"},
      {"scenario: base.yaml\naxes: [office.people_walking]\n", "axes: expected a map"},
      {"scenario: base.yaml\nset: [seed]\naxes: {office.people_walking: [0, 2]}\n", "set: 'seed': expected KEY=VALUE"},
      {"scenario: base.yaml\naxes: {office.people_walking: [0, 2}\n", "line "},
  };
  for (const auto& [text, fragment] : cases) {
    const fs::path file = Write("bad.yaml", text);
    try {
      SweepFile::Load(file);
      ADD_FAILURE() << text << ": accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << text << "\n" << e.what();
    }
  }
}

// Every shipped sweep file loads, and every one of its points is a valid scenario run.
TEST(ShippedSweepFilesTest, EveryPointIsAValidRun) {
  const fs::path folder = fs::path(SEGSLAM_SOURCE_DIR) / "scenarios" / "sweeps";
  int files = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() != ".yaml") continue;
    ++files;
    SCOPED_TRACE(entry.path().string());
    ASSERT_TRUE(SweepFile::Recognize(entry.path()));
    const SweepFile sweep = SweepFile::Load(entry.path());
    EXPECT_GE(sweep.grid.PointCount(), 5);  // "at least five densities"
    const scenes::Scenario base = scenes::LoadScenario(sweep.scenario);
    for (int p = 0; p < sweep.grid.PointCount(); ++p) {
      scenes::Scenario scenario = base;
      std::vector<std::string> overrides = sweep.grid.fixed_overrides;
      for (const std::string& assignment : sweep.grid.PointAssignments(p)) overrides.push_back(assignment);
      for (const std::string& assignment : overrides) {
        const std::size_t equals = assignment.find('=');
        EXPECT_NO_THROW(scenes::ApplyOverride(scenario, assignment.substr(0, equals), assignment.substr(equals + 1)))
            << assignment;
      }
      ScenarioRunRequest request;
      request.scenario_file = sweep.scenario.string();
      EXPECT_NO_THROW(EffectiveBench(scenario, request)) << sweep.grid.PointName(p);
    }
  }
  EXPECT_GE(files, 3);
}

// --segmenter gt replaces the file's simulated segmenter: its strength and refinement
// options have nothing left to act on, so they are dropped rather than refused.
TEST(EffectiveBenchTest, GroundTruthMasksDropTheSegmentersStrengthAndRefinerOptions) {
  scenes::Scenario scenario = scenes::LoadScenario(fs::path(SEGSLAM_SOURCE_DIR) / "scenarios" / "test" / "office_small.yaml");
  scenes::ApplyOverrides(scenario, {"bench.segmenter_strength=2", "bench.refiner.trim_keeps_region_depth=1",
                                    "bench.tracker.min_tracking_inliers=40"});
  ScenarioRunRequest request;
  request.scenario_file = "office_small.yaml";
  const BenchSettings as_written = EffectiveBench(scenario, request);
  EXPECT_EQ(as_written.refiner, std::vector<std::string>{"trim_keeps_region_depth=1"});
  EXPECT_EQ(as_written.segmenter_strength, 2.0);
  request.segmenter = "gt";
  const BenchSettings with_gt = EffectiveBench(scenario, request);
  EXPECT_TRUE(with_gt.refiner.empty());
  EXPECT_EQ(with_gt.segmenter_strength, 1.0);
  EXPECT_EQ(with_gt.tracker, std::vector<std::string>{"min_tracking_inliers=40"});  // the tracker runs in every mode
}

TEST(SweepShardTest, ShardsCoverEveryPointExactlyOnce) {
  for (int n = 1; n <= 4; ++n) {
    for (int p = 0; p < 11; ++p) {
      int owners = 0;
      for (int i = 1; i <= n; ++i) owners += Shard::Parse(std::to_string(i) + "/" + std::to_string(n)).Owns(p) ? 1 : 0;
      EXPECT_EQ(owners, 1) << "point " << p << " of " << n << " shards";
    }
  }
  for (const char* bad : {"0/2", "3/2", "1/0", "1-2", "a/b", "1/2x"}) EXPECT_THROW(Shard::Parse(bad), Error) << bad;
}

// Slurm numbers an array's tasks as --array says (0-9, 1-10, 1-19:2): each gives shards
// 1..N, every one once.
TEST(SweepShardTest, SlurmArrayTasksAreTheShards) {
  const auto shard_of = [](std::map<std::string, std::string> variables) {
    return Shard::FromSlurmArray([variables](const char* name) -> const char* {
      const auto it = variables.find(name);
      return it == variables.end() ? nullptr : it->second.c_str();
    });
  };
  struct Array {
    int first, step, count;
  };
  for (const Array array : {Array{0, 1, 4}, Array{1, 1, 4}, Array{1, 2, 4}, Array{7, 3, 2}}) {
    std::set<int> indices;
    for (int k = 0; k < array.count; ++k) {
      const Shard shard = shard_of({{"SLURM_ARRAY_TASK_ID", std::to_string(array.first + k * array.step)},
                                    {"SLURM_ARRAY_TASK_MIN", std::to_string(array.first)},
                                    {"SLURM_ARRAY_TASK_STEP", std::to_string(array.step)},
                                    {"SLURM_ARRAY_TASK_COUNT", std::to_string(array.count)}});
      EXPECT_EQ(shard.count, array.count);
      indices.insert(shard.index);
    }
    EXPECT_EQ(indices.size(), static_cast<std::size_t>(array.count));
    EXPECT_EQ(*indices.begin(), 1);
    EXPECT_EQ(*indices.rbegin(), array.count);
  }
  // Without MIN and STEP (older Slurm): numbered from 0 in steps of 1.
  EXPECT_EQ(shard_of({{"SLURM_ARRAY_TASK_ID", "2"}, {"SLURM_ARRAY_TASK_COUNT", "3"}}).index, 3);
  // Not an array task, a list such as --array=1,4,9, or garbage: refused, naming what.
  const auto refusal = [&](std::map<std::string, std::string> variables) {
    try {
      shard_of(std::move(variables));
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(refusal({}).find("SLURM_ARRAY_TASK_ID is not set; submit the sweep as a Slurm job array"),
            std::string::npos);
  EXPECT_NE(refusal({{"SLURM_ARRAY_TASK_ID", "9"}, {"SLURM_ARRAY_TASK_MIN", "1"}, {"SLURM_ARRAY_TASK_COUNT", "3"}})
                .find("task 9 is not one of 3 tasks from 1 in steps of 1"),
            std::string::npos);
  EXPECT_NE(refusal({{"SLURM_ARRAY_TASK_ID", "x1"}, {"SLURM_ARRAY_TASK_COUNT", "3"}}).find("SLURM_ARRAY_TASK_ID=x1 is "
                                                                                         "not a whole number"),
            std::string::npos);
}

class SweepCliTest : public segslam::testing::CliScratchTest {
 protected:
  SweepCliTest() : CliScratchTest("segslam_sweep_") {}
};

const std::string kSmallOffice = (fs::path(SEGSLAM_SOURCE_DIR) / "scenarios" / "test" / "office_small.yaml").string();

TEST_F(SweepCliTest, ShardsMergedEqualOneRun) {
  const std::string common = kSmallOffice + " --set office.people_walking=0,2 --set office.people_sitting=1 --frames 12 " +
                             "--repeats 1 --modes plain,mutual,oracle --segmenter gt -q --cache " + (dir_ / "cache").string();
  const CommandOutput whole = Run("sweep " + common + " --out " + (dir_ / "whole").string());
  ASSERT_EQ(whole.exit_code, 0) << whole.stderr_text;
  for (const char* file : {"sweep.json", "sweep_results.json", "report.md", "report.html", "figures/sweep_ate_pass1.png",
                           "figures/sweep_localized_pass2.png", "figures/sweep_map_relative_pass2.png",
                           "figures/sweep_map_relative_within_pass2.png", "figures/sweep_moving_features_pass1.png",
                           "points/office.people_walking=0/results.json",
                           "points/office.people_walking=2/results.json"}) {
    EXPECT_TRUE(fs::exists(dir_ / "whole" / file)) << file;
  }
  const std::string table = ReadText(dir_ / "whole" / "report.md");
  EXPECT_NE(table.find("| office.people\\_walking |"), std::string::npos) << table;  // Markdown escapes '_'
  EXPECT_NE(table.find("![ATE, pass 1 against"), std::string::npos) << table;
  EXPECT_NE(table.find("| mutual/plain ATE p1 | mutual/plain ATE p2 | oracle/plain ATE p1 |"), std::string::npos)
      << table;
  EXPECT_NE(table.find("| plain map-relative p2 \\[m\\] | plain within 0.1 m, 1 deg p2 |"), std::string::npos) << table;
  // Moving features: the sitter gestures, so tracks.json counts it moving at both points
  // (16 % of the features); the two walkers add to that.
  const nlohmann::json results = nlohmann::json::parse(ReadText(dir_ / "whole" / "sweep_results.json"));
  ASSERT_EQ(results["points"].size(), 2u);
  const auto moving_mean = [&](int point) {
    return results["points"][point]["summary"]["pass1"]["mutual"]["moving_feature_share_mean"]["median"].get<double>();
  };
  EXPECT_LT(moving_mean(0), moving_mean(1));
  EXPECT_GT(moving_mean(1), 0.05);

  for (const char* shard : {"1/2", "2/2"}) {
    const CommandOutput part = Run("sweep " + common + " --shard " + shard + " --out " +
                                   (dir_ / ("shard" + std::string(1, shard[0]))).string());
    ASSERT_EQ(part.exit_code, 0) << part.stderr_text;
  }
  // A shard alone does not merge: it holds one of the two points.
  EXPECT_FALSE(fs::exists(dir_ / "shard1" / "report.md"));
  EXPECT_TRUE(fs::exists(dir_ / "shard1" / "points" / "office.people_walking=0" / "results.json"));
  EXPECT_FALSE(fs::exists(dir_ / "shard1" / "points" / "office.people_walking=2" / "results.json"));

  // Merging one shard is refused, naming the missing point.
  const CommandOutput incomplete = Run("sweep merge " + (dir_ / "shard1").string());
  EXPECT_EQ(incomplete.exit_code, 1);
  EXPECT_EQ(LineCount(incomplete.stderr_text), 1) << incomplete.stderr_text;
  EXPECT_NE(incomplete.stderr_text.find("office.people_walking=2"), std::string::npos) << incomplete.stderr_text;

  const CommandOutput merged = Run("sweep merge " + (dir_ / "shard1").string() + " " + (dir_ / "shard2").string() +
                                   " --out " + (dir_ / "merged").string());
  ASSERT_EQ(merged.exit_code, 0) << merged.stderr_text;
  // The merged report points at each point's own report: it is there.
  EXPECT_TRUE(fs::exists(dir_ / "merged" / "points" / "office.people_walking=2" / "report.html"));
  const nlohmann::json a = nlohmann::json::parse(ReadText(dir_ / "whole" / "sweep_results.json"));
  const nlohmann::json b = nlohmann::json::parse(ReadText(dir_ / "merged" / "sweep_results.json"));
  ASSERT_EQ(a["points"].size(), 2u);
  for (std::size_t p = 0; p < 2; ++p) {
    EXPECT_EQ(a["points"][p]["assignments"], b["points"][p]["assignments"]);
    // SLAM with ground-truth masks is deterministic: the same numbers either way.
    EXPECT_EQ(a["points"][p]["summary"], b["points"][p]["summary"]);
  }

  // Run again: every point is kept, nothing is recomputed.
  const CommandOutput again = Run("sweep " + common + " --out " + (dir_ / "whole").string());
  ASSERT_EQ(again.exit_code, 0) << again.stderr_text;
  EXPECT_NE(again.stdout_text.find("done before, kept"), std::string::npos) << again.stdout_text;

  // The same grid with other settings is another sweep: its points are not the ones kept
  // there, and shards of the two do not merge.
  const std::string longer = kSmallOffice + " --set office.people_walking=0,2 --set office.people_sitting=1 --frames 14 " +
                             "--repeats 1 --modes plain,mutual,oracle --segmenter gt -q --cache " + (dir_ / "cache").string();
  const CommandOutput other = Run("sweep " + longer + " --out " + (dir_ / "whole").string());
  EXPECT_EQ(other.exit_code, 1);
  EXPECT_NE(other.stderr_text.find("holds another sweep"), std::string::npos) << other.stderr_text;
  fs::create_directories(dir_ / "other_settings");
  nlohmann::json claimed = nlohmann::json::parse(ReadText(dir_ / "shard2" / "sweep.json"));
  claimed["settings"]["frames"] = 14;
  std::ofstream(dir_ / "other_settings" / "sweep.json") << claimed.dump();
  const CommandOutput mixed = Run("sweep merge " + (dir_ / "shard1").string() + " " +
                                  (dir_ / "other_settings").string() + " --out " + (dir_ / "mixed").string());
  EXPECT_EQ(mixed.exit_code, 1);
  EXPECT_NE(mixed.stderr_text.find("was run with other settings"), std::string::npos) << mixed.stderr_text;

  // A scenario file edited since its sweep ran: the same path, the same options, another
  // world; its folder's points are not kept as this sweep's.
  const fs::path copy = dir_ / "office_small_copy.yaml";
  fs::copy_file(kSmallOffice, copy);
  const std::string common_on_copy = copy.string() + common.substr(kSmallOffice.size());
  const CommandOutput on_copy = Run("sweep " + common_on_copy + " --out " + (dir_ / "edited").string() + " --shard 1/2");
  ASSERT_EQ(on_copy.exit_code, 0) << on_copy.stderr_text;
  std::string text = ReadText(copy);
  const std::size_t seed = text.find("seed: 5");
  ASSERT_NE(seed, std::string::npos);
  text.replace(seed, 7, "seed: 6");
  std::ofstream(copy) << text;
  const CommandOutput edited = Run("sweep " + common_on_copy + " --out " + (dir_ / "edited").string() + " --shard 1/2");
  EXPECT_EQ(edited.exit_code, 1);
  EXPECT_NE(edited.stderr_text.find("holds another sweep"), std::string::npos) << edited.stderr_text;
}

// A sweep file over the simulated segmenter's error strength: strength 0 is the ground
// truth (raw mIoU 100), and raw masks get worse as it grows; --set narrows the file's axis.
TEST_F(SweepCliTest, SweepFileOverSegmentationErrorStrength) {
  const fs::path file = dir_ / "strength.yaml";
  std::ofstream(file) << "name: strength_study\nscenario: " << kSmallOffice
                      << "\nset: [bench.repeats=1, office.people_walking=1]\n"
                      << "axes:\n  bench.segmenter_strength: [0, 1, 3, 5]\n";
  const CommandOutput result = Run("sweep " + file.string() + " --set bench.segmenter_strength=0,3 --frames 12 " +
                                   "--modes mutual -q --cache " + (dir_ / "cache").string() + " --out " +
                                   (dir_ / "out").string());
  ASSERT_EQ(result.exit_code, 0) << result.stdout_text << result.stderr_text;
  EXPECT_NE(result.stdout_text.find("segmenter fcis-like@3"), std::string::npos) << result.stdout_text;
  const nlohmann::json sweep = nlohmann::json::parse(ReadText(dir_ / "out" / "sweep.json"));
  EXPECT_EQ(sweep["sweep_file"], file.string());
  const std::string report = ReadText(dir_ / "out" / "report.md");
  EXPECT_NE(report.find("segslam sweep: strength\\_study"), std::string::npos) << report;  // '_' escaped
  EXPECT_NE(report.find("segmenter fcis-like@0, fcis-like@3 (per point)"), std::string::npos) << report;
  const nlohmann::json results = nlohmann::json::parse(ReadText(dir_ / "out" / "sweep_results.json"));
  ASSERT_EQ(results["points"].size(), 2u);
  auto raw_miou = [&](int p) {
    return results["points"][p]["summary"]["pass1"]["mutual"]["seg_raw_miou"]["median"].get<double>();
  };
  EXPECT_EQ(results["points"][0]["assignments"], nlohmann::json::array({"bench.segmenter_strength=0"}));
  EXPECT_NEAR(raw_miou(0), 1.0, 1e-9);
  EXPECT_LT(raw_miou(1), 0.9);
  const nlohmann::json point = nlohmann::json::parse(
      ReadText(dir_ / "out" / "points" / "bench.segmenter_strength=3" / "results.json"));
  EXPECT_EQ(point["bench"]["segmenter_strength"], 3.0);
  // Without an --out the report goes to reports/<sweep name>; the strength axis needs a
  // simulated segmenter, so --segmenter gt is refused before any work.
  const CommandOutput refused = Run("sweep " + file.string() + " --segmenter gt -q --cache " + (dir_ / "cache2").string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_EQ(LineCount(refused.stderr_text), 1) << refused.stderr_text;
  EXPECT_NE(refused.stderr_text.find("segmenter is gt"), std::string::npos) << refused.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "cache2"));
}

TEST_F(SweepCliTest, BadInputIsOneLineBeforeAnyWork) {
  const std::string out = " --out " + (dir_ / "out").string() + " --cache " + (dir_ / "cache").string() + " -q";
  const struct {
    std::string arguments, message;
  } cases[] = {
      {"--set office.people_walking", "expected KEY=VALUE"},
      {"--set office.walkers=1,2", "office.walkers"},
      {"--set office.people_walking=1,-3", "people_walking"},
      {"--set office.people_walking=1,2 --shard 3/2", "--shard"},
      {"--set bench.tracker.orb.max_feature=500,1000", "unknown field 'orb.max_feature'"},
      {"--set bench.refiner.trim_keeps_region_depth=0,2", "trim_keeps_region_depth: expected 0 or 1"},
      {"--set bench.refiner.trim_keeps_region_depth=0,1 --segmenter gt", "the segmenter is gt"},
      {"--set office.people_walking=1,2 --emit-sbatch " + kSmallOffice, "is not a folder; --emit-sbatch takes"},
      {"--set office.people_walking=1,2 --emit-sbatch " + (dir_ / "jobs").string() + " --shard 1/2", "leave --shard out"},
      {"--set office.people_walking=1,2 --shard slurm", "SLURM_ARRAY_TASK_ID is not set"},
  };
  for (const auto& c : cases) {
    const std::string arguments = "sweep " + kSmallOffice + " " + c.arguments + out;
    const CommandOutput result = Run(arguments);
    EXPECT_EQ(result.exit_code, 1) << arguments;
    EXPECT_EQ(LineCount(result.stderr_text), 1) << arguments << "\n" << result.stderr_text;
    EXPECT_NE(result.stderr_text.find(c.message), std::string::npos) << arguments << "\n" << result.stderr_text;
    EXPECT_FALSE(fs::exists(dir_ / "cache")) << arguments;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << arguments;
  }
}

// Every shipped suite file passes `scenario suite --check`: each entry's scenario,
// overrides, bench settings and thresholds are valid, and nothing is generated or run.
TEST_F(SweepCliTest, ShippedSuiteFilesPassTheirCheck) {
  const fs::path folder = fs::path(SEGSLAM_SOURCE_DIR) / "scenarios" / "suites";
  int files = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() != ".yaml") continue;
    ++files;
    const CommandOutput result = Run("scenario suite " + entry.path().string() + " --check --cache " +
                                     (dir_ / "cache").string() + " --out " + (dir_ / "out").string());
    EXPECT_EQ(result.exit_code, 0) << entry.path() << "\n" << result.stderr_text;
    EXPECT_NE(result.stdout_text.find("entries checked"), std::string::npos) << result.stdout_text;
  }
  EXPECT_GE(files, 1);
  EXPECT_FALSE(fs::exists(dir_ / "cache"));
  EXPECT_FALSE(fs::exists(dir_ / "out"));

  // --check refuses what a run would refuse, in one line.
  const fs::path late = dir_ / "late_suite.yaml";
  std::ofstream(late) << "name: late\nentries:\n"
                      << "  - {name: a, scenario: " << kSmallOffice << ", tables: [ate]}\n"
                      << "  - {name: b, scenario: " << kSmallOffice << ", set: [bench.segmenter=magic], tables: [ate]}\n";
  const CommandOutput refused = Run("scenario suite " + late.string() + " --check");
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_EQ(LineCount(refused.stderr_text), 1) << refused.stderr_text;
  EXPECT_NE(refused.stderr_text.find("entry b: "), std::string::npos) << refused.stderr_text;
}

// `segslam scenario suite`: entries joined into the paper's tables, and a bad suite file
// refused in one line before any work.
TEST_F(SweepCliTest, SuiteJoinsItsEntriesIntoThePapersTables) {
  const fs::path suite = dir_ / "tiny_suite.yaml";
  std::ofstream(suite) << "name: tiny\nentries:\n"
                       << "  - {name: office_a, scenario: " << kSmallOffice << ", tables: [ate, segmentation]}\n"
                       << "  - {name: office_b, scenario: " << kSmallOffice << ", set: [seed=9], tables: [relocalization]}\n"
                       << "  - {name: office_c, scenario: " << kSmallOffice << ", set: [seed=10], tables: [relocalization]}\n";
  const CommandOutput result = Run("scenario suite " + suite.string() + " --frames 10 --repeats 1 --modes plain,mutual -q" +
                                   " --cache " + (dir_ / "cache").string() + " --out " + (dir_ / "out").string());
  ASSERT_EQ(result.exit_code, 0) << result.stdout_text << result.stderr_text;
  for (const char* file : {"report.md", "report.html", "suite_results.json", "office_a/results.json",
                           "office_b/results.json", "office_c/results.json"}) {
    EXPECT_TRUE(fs::exists(dir_ / "out" / file)) << file;
  }
  const std::string markdown = ReadText(dir_ / "out" / "report.md");
  EXPECT_NE(markdown.find("Table I: ATE"), std::string::npos) << markdown;
  EXPECT_NE(markdown.find("Table III: relocalization"), std::string::npos) << markdown;
  // Each entry appears in the tables it asked for and no other.
  EXPECT_NE(result.stdout_text.find("office_a pass1 |"), std::string::npos) << result.stdout_text;
  EXPECT_EQ(result.stdout_text.find("office_b pass1 |"), std::string::npos) << result.stdout_text;
  const nlohmann::json joined = nlohmann::json::parse(ReadText(dir_ / "out" / "suite_results.json"));
  ASSERT_EQ(joined["entries"].size(), 3u);
  EXPECT_EQ(joined["entries"][1]["overrides"], nlohmann::json::array({"seed=9"}));
  // Table III also over all routes, as the paper gives it: each mode's per-route medians
  // of pass 2's ATE, here two routes, so their mean, min and max.
  EXPECT_NE(result.stdout_text.find("all 2 routes: median [min, max] |"), std::string::npos) << result.stdout_text;
  for (const std::string mode : {"plain", "mutual"}) {
    std::vector<double> route_ate;
    for (const char* entry : {"office_b", "office_c"}) {
      const nlohmann::json route = nlohmann::json::parse(ReadText(dir_ / "out" / entry / "results.json"));
      route_ate.push_back(route["summary"]["pass2"][mode]["ate_rmse_m"]["median"].get<double>());
    }
    const nlohmann::json& over_routes = joined["relocalization_over_routes"][mode]["ate_rmse_m"];
    ASSERT_TRUE(over_routes.is_object()) << joined.dump(2);
    EXPECT_EQ(over_routes["routes"], 2) << mode;
    EXPECT_NEAR(over_routes["median"].get<double>(), (route_ate[0] + route_ate[1]) / 2, 1e-12) << mode;
    EXPECT_EQ(over_routes["min"].get<double>(), std::min(route_ate[0], route_ate[1])) << mode;
    EXPECT_EQ(over_routes["max"].get<double>(), std::max(route_ate[0], route_ate[1])) << mode;
  }

  const fs::path bad = dir_ / "bad_suite.yaml";
  std::ofstream(bad) << "name: bad\nentries:\n"
                     << "  - {name: a, scenario: " << kSmallOffice << ", tables: [ate, table9]}\n";
  const CommandOutput refused = Run("scenario suite " + bad.string() + " -q --cache " + (dir_ / "cache2").string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_EQ(LineCount(refused.stderr_text), 1) << refused.stderr_text;
  EXPECT_NE(refused.stderr_text.find("entries[0]: tables: unknown table 'table9'"), std::string::npos)
      << refused.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "cache2"));

  // A bad bench setting in the last entry stops the suite before the first one runs; an
  // entry named .. (its report folder) is refused.
  const fs::path late = dir_ / "late_suite.yaml";
  std::ofstream(late) << "name: late\nentries:\n"
                      << "  - {name: a, scenario: " << kSmallOffice << ", tables: [ate]}\n"
                      << "  - {name: b, scenario: " << kSmallOffice << ", set: [bench.segmenter=magic], tables: [ate]}\n";
  const CommandOutput late_refused = Run("scenario suite " + late.string() + " -q --cache " + (dir_ / "cache3").string() +
                                         " --out " + (dir_ / "late_out").string());
  EXPECT_EQ(late_refused.exit_code, 1);
  EXPECT_NE(late_refused.stderr_text.find("entry b: "), std::string::npos) << late_refused.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "cache3"));
  const fs::path dots = dir_ / "dots_suite.yaml";
  std::ofstream(dots) << "name: dots\nentries:\n  - {name: '..', scenario: " << kSmallOffice << ", tables: [ate]}\n";
  const CommandOutput dots_refused = Run("scenario suite " + dots.string() + " -q --cache " + (dir_ / "cache4").string());
  EXPECT_EQ(dots_refused.exit_code, 1);
  EXPECT_NE(dots_refused.stderr_text.find("not . or .."), std::string::npos) << dots_refused.stderr_text;
}

}  // namespace
}  // namespace segslam::harness
