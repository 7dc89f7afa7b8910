// The settings of a scenario run: the scenario's `bench:` section (modes, repeats, the
// simulated segmenter, tracker and refiner overrides), read and checked, and the options
// they give the runs. Command-line options of `scenario run`, `sweep` and `suite` override
// it (harness/scenario_runner.h: EffectiveBench).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "harness/run_config.h"
#include "mutual/slam_mode.h"
#include "seg/refiner.h"
#include "slam/tracker.h"

namespace segslam::harness {

// The scenario's `bench:` section; command-line options override it.
struct BenchSettings {
  std::vector<std::string> modes = mutual::PaperModeNames();  // the oracle only when named
  int repeats = 10;  // runs per mode, differing by the segmenter's seed (the paper: 10)
  // Simulated segmenter preset (seg/simulated_segmenter.h) for mask-moveable and mutual;
  // "gt" uses the dataset's ground-truth masks (then every mode is deterministic).
  std::string segmenter = "fcis-like";
  // Scales every error of the simulated segmenter: 0 = ground truth, 1 = the preset, 2 =
  // twice as bad; a sweep axis for segmentation error strength. [0, 10].
  double segmenter_strength = 1.0;
  std::uint64_t seed = 1;  // repeat r (0-based) uses seed + r
  // "name=value" overrides of the mutual loop's refinement (seg/refiner_options.h),
  // from `refiner: {name: value, ...}`; a sweep axis as bench.refiner.NAME. Only the loop
  // refines, so they need a simulated segmenter.
  std::vector<std::string> refiner;
  // "name=value" overrides of the tracker (slam/tracker_options.h) in every
  // mode, from `tracker: {name: value, ...}`; nested names as orb: {max_features: 1500}
  // or orb.max_features. A sweep axis as bench.tracker.NAME.
  std::vector<std::string> tracker;
  // Also run plain on the scenario's static twin (scenes::StaticTwin: the same world with
  // nothing moving), the yardstick of how much error the traffic adds: results and
  // `expect:` get MODE.traffic_error_removed (harness/scenario_expectations.h).
  bool static_twin = false;
  // Repeat r runs every mode (and the static twin) with the ORB feature budget shifted
  // by FeatureBudgetShift(r) x feature_jitter features: 0, +1, -1, +2, -2, ... A run of
  // SLAM is chaotic: a feature more or less changes which keyframes are made, and one
  // run's ATE moves by about a tenth (docs/metrics.md), so without a spread of its own a
  // deterministic mode, plain above all, is one draw. With a jitter every mode runs
  // `repeats` times and the medians are over those runs. 0 = off.
  int feature_jitter = 0;

  // Throws segslam::Error naming `origin` and the key on unknown keys or bad values.
  static BenchSettings FromYaml(const YAML::Node& bench, const std::string& origin);
  // Empty when valid, else what is wrong.
  std::string Check() const;
  // The run of `mode` with the segmenter's seed `seed`: plain reads no masks, the oracle
  // the ground truth's (its verdicts name their ids), mask-moveable and mutual the
  // segmenter's (or the ground truth's, segmenter gt). `mode` must be one of `modes`'s
  // names (Check()).
  RunConfig RunConfigFor(const std::string& mode, std::uint64_t seed) const;
  // Without a simulated segmenter or a feature jitter SLAM is deterministic: one run says
  // everything.
  bool ModeIsDeterministic(const std::string& mode) const {
    return feature_jitter == 0 && RunConfigFor(mode, seed).IsDeterministic();
  }
  // 0, +1, -1, +2, -2, ... for repeat 0, 1, 2, 3, 4, ...
  static int FeatureBudgetShift(int repeat);
  // The ORB feature budget of repeat `repeat` (0-based): the tracker's, jittered.
  int FeatureBudgetFor(int repeat) const;
  // The tracker's "name=value" overrides of repeat `repeat`: `tracker`, and the jittered
  // feature budget when feature_jitter is on.
  std::vector<std::string> TrackerAssignmentsFor(int repeat) const;
  // The segmenter as reports name it: "gt", "fcis-like", "fcis-like@2".
  std::string SegmenterLabel() const;
  // The refinement options of the mutual loop: the defaults with `refiner` set.
  seg::RefinerOptions LoopRefinerOptions() const;
  // The tracker's options: the defaults with `tracker` set.
  slam::TrackerOptions TrackerOverrides() const;
};

}  // namespace segslam::harness
