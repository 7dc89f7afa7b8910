// The one check of a run's mode and masks (harness/run_config.h): every rule with a case
// that keeps it and one that breaks it, and what a config says of itself.
#include "harness/run_config.h"

#include <gtest/gtest.h>

#include <string>

#include "core/error.h"
#include "harness/bench_settings.h"

namespace segslam::harness {
namespace {

std::string Refusal(const std::string& mode, const std::string& masks, const std::string& segmenter,
                    double strength = 1.0) {
  try {
    MakeRunConfig("run", mode, masks, segmenter, 1, strength);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(RunConfigTest, EachMaskSourceAsTheWordsSayIt) {
  const RunConfig plain = MakeRunConfig("run", "plain", "gt", "fcis-like", 1, 1.0);
  EXPECT_EQ(plain.masks.kind, MaskSource::Kind::kNone) << "plain reads no masks, whatever was given";
  EXPECT_EQ(plain.masks.Describe(), "none");

  const RunConfig gt = MakeRunConfig("run", "mask-moveable", "gt", "", 1, 1.0);
  EXPECT_EQ(gt.masks.kind, MaskSource::Kind::kGroundTruth);
  EXPECT_EQ(gt.masks.Describe(), "gt");

  const RunConfig external = MakeRunConfig("run", "mutual", "/data/masks", "", 1, 1.0);
  EXPECT_EQ(external.masks.kind, MaskSource::Kind::kExternal);
  EXPECT_EQ(external.masks.Describe(), "external /data/masks");

  const RunConfig simulated = MakeRunConfig("run", "mutual", "gt", "fcis-like", 4, 2.0);
  EXPECT_EQ(simulated.masks.kind, MaskSource::Kind::kSimulated);
  EXPECT_EQ(simulated.masks.Describe(), "simulated fcis-like@2 seed 4");
}

TEST(RunConfigTest, OnlyMutualWithASegmentersMasksRefinesAndOnlyASimulatedSegmenterHasASeed) {
  EXPECT_TRUE(MakeRunConfig("run", "mutual", "gt", "poor", 1, 1.0).RefinesMasks());
  EXPECT_TRUE(MakeRunConfig("run", "mutual", "/m", "", 1, 1.0).RefinesMasks());
  EXPECT_FALSE(MakeRunConfig("run", "mutual", "gt", "", 1, 1.0).RefinesMasks());
  EXPECT_FALSE(MakeRunConfig("run", "mask-moveable", "gt", "poor", 1, 1.0).RefinesMasks());
  EXPECT_FALSE(MakeRunConfig("run", "oracle", "gt", "", 1, 1.0).RefinesMasks());

  EXPECT_FALSE(MakeRunConfig("run", "mask-moveable", "gt", "poor", 1, 1.0).IsDeterministic());
  EXPECT_TRUE(MakeRunConfig("run", "mutual", "/m", "", 1, 1.0).IsDeterministic());
  EXPECT_TRUE(MakeRunConfig("run", "plain", "gt", "poor", 1, 1.0).IsDeterministic());
}

TEST(RunConfigTest, RefusalsNameTheCommandAndTheRule) {
  EXPECT_NE(Refusal("slow", "gt", "").find("run: unknown SLAM mode 'slow'"), std::string::npos);
  EXPECT_NE(Refusal("mutual", "gt", "perfect").find("unknown segmenter 'perfect'"), std::string::npos);
  EXPECT_NE(Refusal("mutual", "/m", "fcis-like").find("exclude each other"), std::string::npos);
  EXPECT_NE(Refusal("oracle", "gt", "fcis-like").find("mode oracle takes the dataset's ground-truth masks"),
            std::string::npos);
  EXPECT_NE(Refusal("oracle", "/m", "").find("mode oracle"), std::string::npos);
  EXPECT_NE(Refusal("mutual", "gt", "", 2.0).find("give --segmenter too"), std::string::npos);
  EXPECT_NE(Refusal("mutual", "gt", "fcis-like", 11).find("[0, 10]"), std::string::npos);
  EXPECT_EQ(Refusal("oracle", "gt", ""), "");
  EXPECT_EQ(Refusal("mutual", "gt", "fcis-like", 0), "");
}

// Fields of the simulated segmenter's preset set by name: applied over the preset and its
// strength, named in the description, refused without a simulated segmenter, on an unknown
// field or out of range.
TEST(RunConfigTest, SegmenterOptionsOverrideThePresetByName) {
  RunConfigWords words;
  words.segmenter = "fcis-like";
  words.strength = 2.0;
  words.segmenter_options = {"hole_prob=0", "boundary_jitter_px=3"};
  const RunConfig config = words.ToConfig("run");
  EXPECT_EQ(config.masks.Describe(), "simulated fcis-like@2 seed 1 [hole_prob=0, boundary_jitter_px=3]");
  const seg::SimulatedSegmenterOptions options = config.masks.SimulatedOptions();
  const seg::SimulatedSegmenterOptions preset = seg::SimulatedSegmenterOptions::Preset("fcis-like");
  EXPECT_EQ(options.hole_prob, 0.0);
  EXPECT_EQ(options.boundary_jitter_px, 3.0);
  EXPECT_EQ(options.cut_prob, preset.cut_prob) << "a field not named keeps the preset's value";
  EXPECT_EQ(options.strength, 2.0);
  EXPECT_EQ(PresetWithOverrides("fcis-like", words.segmenter_options), "fcis-like[hole_prob=0,boundary_jitter_px=3]");
  EXPECT_EQ(PresetWithOverrides("poor", {}), "poor");

  const auto refusal = [&](RunConfigWords changed) {
    try {
      changed.ToConfig("run");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  RunConfigWords no_segmenter = words;
  no_segmenter.segmenter.clear();
  no_segmenter.strength = 1.0;
  EXPECT_NE(refusal(no_segmenter).find("run: --segmenter-option"), std::string::npos);
  RunConfigWords unknown = words;
  unknown.segmenter_options = {"hole_size=3"};
  EXPECT_NE(refusal(unknown).find("hole_size"), std::string::npos);
  RunConfigWords out_of_range = words;
  out_of_range.segmenter_options = {"miss_prob=2"};
  EXPECT_NE(refusal(out_of_range).find("miss_prob"), std::string::npos) << refusal(out_of_range);
  RunConfigWords plain = words;
  plain.mode = "plain";
  EXPECT_EQ(plain.ToConfig("run").masks.kind, MaskSource::Kind::kNone) << "plain reads no masks, whatever was given";
}

// A scenario's runs: the segmenter for mask-moveable and mutual, the ground truth for the
// oracle, nothing for plain; the strength only where a segmenter runs.
TEST(RunConfigTest, ScenarioRunsTakeTheirMasksFromTheBenchSettings) {
  BenchSettings bench;
  bench.modes = {"plain", "mask-moveable", "mutual", "oracle"};
  bench.segmenter = "fcis-like";
  bench.segmenter_strength = 2.0;
  EXPECT_EQ(bench.RunConfigFor("plain", 3).masks.kind, MaskSource::Kind::kNone);
  EXPECT_EQ(bench.RunConfigFor("oracle", 3).masks.kind, MaskSource::Kind::kGroundTruth);
  const RunConfig mutual = bench.RunConfigFor("mutual", 3);
  EXPECT_EQ(mutual.masks.Describe(), "simulated fcis-like@2 seed 3");
  EXPECT_TRUE(mutual.RefinesMasks());
  EXPECT_EQ(bench.RunConfigFor("mask-moveable", 5).masks.seed, 5u);
  bench.segmenter = "gt";
  bench.segmenter_strength = 1.0;
  EXPECT_EQ(bench.RunConfigFor("mutual", 3).masks.kind, MaskSource::Kind::kGroundTruth);
  EXPECT_TRUE(bench.ModeIsDeterministic("mutual"));
}

}  // namespace
}  // namespace segslam::harness
