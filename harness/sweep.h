// A sweep: one scenario run (harness/scenario_runner.h) per point of a grid over scenario
// parameters, e.g. the density of dynamic objects, and a table and plots of ATE,
// relocalization and segmentation against the parameter, per mode.
//
// Each point is an independent job keyed by its assignments ("city.moving_cars=8"): it
// writes OUT/points/<key>/ (a whole scenario report, results.json included), so a sweep
// can be split over machines with --shard i/n (point p, counted from 0 in grid order,
// belongs to shard p % n + 1) and merged from the shards' folders afterwards. A point
// whose results.json exists with the same assignments and code version is not run again,
// so an interrupted sweep resumes where it stopped.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

namespace segslam::harness {

// One swept key and its values, from "--set key=v1,v2,v3". A value that starts with '['
// (a vector such as [0,0.5,0]) is one value.
struct SweepAxis {
  std::string key;
  std::vector<std::string> values;
};

// Where each value of an axis goes on a plot's x axis, in the order to draw them: the
// numbers, ascending, where every value is a distinct number (a sweep may list them
// either way, e.g. distances from far to near); else the values in their order at 0, 1,
// 2, ... (the plot's ticks then count points).
struct AxisPlacement {
  bool numeric = true;
  std::vector<double> x;                  // strictly increasing
  std::vector<std::size_t> value_index;   // the axis value drawn at x[k]
};
AxisPlacement PlaceAxisOnPlot(const SweepAxis& axis);

// The grid: every --set with more than one value is an axis (the first varies slowest);
// the others are fixed overrides applied to every point.
struct SweepGrid {
  std::vector<SweepAxis> axes;
  std::vector<std::string> fixed_overrides;  // KEY=VALUE

  // Throws segslam::Error on a --set without '=' or with an empty value.
  static SweepGrid FromSetOptions(const std::vector<std::string>& set_options);
  // This grid with command-line --set options laid over it: KEY=V1,V2,... replaces KEY's
  // axis in place, or adds an axis after the others; KEY=VALUE fixes KEY for every point
  // (its axis, if it had one, goes). Throws as FromSetOptions.
  SweepGrid WithSetOptions(const std::vector<std::string>& set_options) const;
  int PointCount() const;
  // The assignments of point `index` (0-based, grid order): one KEY=VALUE per axis.
  std::vector<std::string> PointAssignments(int index) const;
  // A folder name for the point: its assignments, '__'-joined, other characters than
  // [A-Za-z0-9._=-] replaced by '_'.
  std::string PointName(int index) const;
  nlohmann::json ToJson() const;
  static SweepGrid FromJson(const nlohmann::json& json, const std::string& origin);
};

// A sweep file: a study in one file, run by `segslam sweep FILE` (scenarios/sweeps/):
//
//   name: office_density                    # optional; default the file's stem
//   scenario: ../office_walking_xyz.yaml    # relative to the sweep file
//   set: [bench.repeats=3]                  # optional: KEY=VALUE for every point
//   axes:                                   # KEY: [V1, V2, ...]; the first varies slowest
//     office.people_walking: [0, 1, 2, 3, 4]
//
// Keys are scenario keys, `bench.*` included (bench.segmenter_strength sweeps the
// segmentation error strength). A value that is itself a list ([0, 0.5, 0]) is one value.
struct SweepFile {
  std::string name;
  std::filesystem::path scenario;
  SweepGrid grid;

  // True for a YAML mapping with `axes:` at its top level (a scenario file has none).
  static bool Recognize(const std::filesystem::path& file);
  // Throws segslam::Error naming the file and the key on malformed YAML, an unknown key,
  // a missing scenario, an axis with fewer than two values or a malformed set: entry.
  // Whether the keys exist in the scenario is checked when the points are built.
  static SweepFile Load(const std::filesystem::path& file);
};

// "i/n" with 1 <= i <= n; throws segslam::Error naming the text otherwise.
struct Shard {
  int index = 1;
  int count = 1;
  // "I/N", or "slurm": the task's place in its Slurm job array (FromSlurmArray, from this
  // process's environment). Throws segslam::Error naming what is wrong.
  static Shard Parse(const std::string& text);
  // Task SLURM_ARRAY_TASK_ID of an array of SLURM_ARRAY_TASK_COUNT tasks, numbered from
  // SLURM_ARRAY_TASK_MIN in steps of SLURM_ARRAY_TASK_STEP (sbatch --array=0-9, 1-10 and
  // 1-19:2 all work; a list such as 1,4,9 does not, and is refused). `variable` looks
  // one up (nullptr: not set).
  static Shard FromSlurmArray(const std::function<const char*(const char*)>& variable);
  bool Owns(int point) const { return point % count + 1 == index; }
};

// The merged sweep: reads OUT/sweep.json (the grid) from `inputs[0]` and every point's
// results.json from whichever of `inputs` holds it, copies point results into `out_dir`
// when they come from elsewhere, and writes out_dir/sweep_results.json, report.md,
// report.html and figures/sweep_*.png. Throws segslam::Error naming the missing points
// when a point has no results in any input, or when the inputs hold different grids.
// Returns a short summary table as text for the terminal.
std::string MergeSweep(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& out_dir);

}  // namespace segslam::harness
