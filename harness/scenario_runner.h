// One scenario run as a function, shared by `segslam scenario run` (one scenario, exit
// code from its thresholds) and `segslam sweep` (one run per point of a parameter grid).
#pragma once

#include <string>
#include <vector>

#include "harness/scenario_report.h"
#include "scenes/scenario.h"

namespace segslam::harness {

struct ScenarioRunRequest {
  std::string scenario_file;
  std::string out_dir;                 // report directory; empty = reports/<scenario name>
  std::string cache_dir = "data/cache";
  std::string modes;                   // comma-separated; empty = the scenario's bench.modes
  int repeats = 0;                     // 0 = the scenario's bench.repeats
  std::string segmenter;               // empty = the scenario's bench.segmenter
  int frames = 0;                      // first N frames per pass; 0 = all
  int jobs = 1;                        // runs at a time (each on its own thread)
  std::string junit_file;              // empty = no JUnit XML
  std::string gl = "osmesa";
  std::vector<std::string> overrides;  // KEY=VALUE scenario overrides (--set)
  bool quiet = false;                  // no progress bars
  bool verify = false;                 // hash a cached dataset's files on every use, not only the first
  std::string progress_prefix;         // put before each progress line, e.g. "[point 2/5] "
};

// The bench settings a run of `scenario` (overrides applied) uses: its bench: section with
// the request's modes, repeats and segmenter laid over it. --segmenter gt sets the
// segmenter strength back to 1 and drops the refiner options (ground truth has no errors
// to scale, and is not refined). Throws
// segslam::Error naming the scenario file on bad settings.
BenchSettings EffectiveBench(const scenes::Scenario& scenario, const ScenarioRunRequest& request);

// Loads the scenario with its overrides, checks bench settings and expect: thresholds
// (throwing segslam::Error before any work on a bad one), generates the dataset or takes
// it from the cache, runs every mode and repeat, scores them, draws the figures and
// writes scenario.yaml, results.json, report.md, report.html (and the JUnit file) into
// the report directory. Returns the report with its checks.
ScenarioReport RunScenarioToReport(const ScenarioRunRequest& request);

}  // namespace segslam::harness
