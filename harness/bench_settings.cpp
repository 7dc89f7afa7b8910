// BenchSettings (harness/bench_settings.h): the `bench:` section read from YAML and
// checked, and the segmenter, tracker and refiner options it gives the runs.
#include "harness/bench_settings.h"

#include <limits>
#include <set>

#include <fmt/format.h>

#include "core/error.h"
#include "core/strings.h"
#include "harness/dataset_run.h"
#include "seg/refiner_options.h"
#include "seg/simulated_segmenter.h"
#include "slam/tracker_options.h"

namespace segslam::harness {

namespace {

// "name=value" for each leaf of a mapping of options. Nested mappings join their keys
// with '.', so `orb: {max_features: 1500}` (what --set bench.tracker.orb.max_features
// writes) and `orb.max_features: 1500` say the same.
void AppendOptionAssignments(const YAML::Node& options, const std::string& prefix, const std::string& where,
                             std::vector<std::string>* assignments) {
  if (!options.IsMap()) throw Error(where + ": expected a mapping of option: value");
  for (const auto& option : options) {
    const std::string name = prefix + option.first.Scalar();
    if (option.second.IsMap()) {
      AppendOptionAssignments(option.second, name + ".", where, assignments);
    } else if (option.second.IsScalar()) {
      assignments->push_back(name + "=" + option.second.Scalar());
    } else {
      throw Error(where + ": " + name + ": expected a number");
    }
  }
}

}  // namespace

BenchSettings BenchSettings::FromYaml(const YAML::Node& bench, const std::string& origin) {
  BenchSettings settings;
  if (!bench || bench.IsNull()) return settings;
  if (!bench.IsMap()) throw Error(origin + ": bench: expected a mapping");
  for (const auto& entry : bench) {
    const std::string key = entry.first.Scalar();
    const YAML::Node& value = entry.second;
    try {
      if (key == "modes") {
        settings.modes = value.IsSequence() ? value.as<std::vector<std::string>>() : Split(value.as<std::string>(), ',');
      } else if (key == "repeats") {
        settings.repeats = value.as<int>();
      } else if (key == "segmenter") {
        settings.segmenter = value.as<std::string>();
      } else if (key == "segmenter_strength") {
        settings.segmenter_strength = value.as<double>();
      } else if (key == "seed") {
        settings.seed = value.as<std::uint64_t>();
      } else if (key == "refiner") {
        AppendOptionAssignments(value, "", origin + ": bench.refiner", &settings.refiner);
      } else if (key == "tracker") {
        AppendOptionAssignments(value, "", origin + ": bench.tracker", &settings.tracker);
      } else if (key == "feature_jitter") {
        settings.feature_jitter = value.as<int>();
      } else if (key == "static_twin") {
        if (!value.IsScalar() || !YAML::convert<bool>::decode(value, settings.static_twin)) {
          throw Error(origin + ": bench.static_twin: expected true or false, got '" +
                      PrintableText(value.IsScalar() ? value.Scalar() : "a list or mapping") + "'");
        }
      } else {
        throw Error(origin + ": unknown key 'bench." + key +
                    "' (known: modes, repeats, segmenter, segmenter_strength, seed, refiner, tracker, static_twin, "
                    "feature_jitter)");
      }
    } catch (const YAML::Exception& e) {
      throw Error(origin + ": bench." + key + ": " + e.msg);
    }
  }
  const std::string problem = settings.Check();
  if (!problem.empty()) throw Error(origin + ": bench: " + problem);
  return settings;
}

std::string BenchSettings::Check() const {
  if (modes.empty()) return "modes: at least one of plain, mask-moveable, mutual, mutual-sparse, oracle";
  std::set<std::string> seen;
  for (const std::string& mode : modes) {
    if (!Contains(mutual::SlamModeNames(), mode)) {
      return "modes: unknown mode '" + mode + "' (plain, mask-moveable, mutual, mutual-sparse or oracle)";
    }
    if (!seen.insert(mode).second) return "modes: '" + mode + "' twice";
  }
  if (repeats < 1) return fmt::format("repeats: must be >= 1 (got {})", repeats);
  const std::vector<std::string> presets = seg::SimulatedSegmenterOptions::PresetNames();
  if (segmenter != "gt" && !Contains(presets, segmenter)) {
    return "segmenter: unknown '" + segmenter + "' (gt or " + Join(presets, ", ") + ")";
  }
  if (!(segmenter_strength >= 0 && segmenter_strength <= 10)) {
    return fmt::format("segmenter_strength: must be in [0, 10] (got {})", segmenter_strength);
  }
  if (segmenter == "gt" && segmenter_strength != 1.0) {
    return "segmenter_strength: scales a simulated segmenter's errors; ground-truth masks (gt) have none";
  }
  if (!refiner.empty()) {
    if (segmenter == "gt") return "refiner: the mutual loop refines a simulated segmenter's masks; ground-truth masks (gt) are not refined";
    try {
      std::string problem;
      if (!LoopRefinerOptions().IsValid(&problem)) return "refiner: " + problem;
    } catch (const Error& e) {
      return std::string("refiner: ") + e.what();
    }
  }
  int budget = 0;
  try {
    budget = TrackerOverrides().orb.max_features;
  } catch (const Error& e) {
    return std::string("tracker: ") + e.what();
  }
  if (feature_jitter < 0) return fmt::format("feature_jitter: must be >= 0 (got {})", feature_jitter);
  const int lowest_shift = -((repeats - 1) / 2);  // FeatureBudgetShift's most negative over the repeats
  const int highest_shift = repeats / 2;
  if (feature_jitter > 0 && budget + lowest_shift * static_cast<long long>(feature_jitter) < 1) {
    return fmt::format("feature_jitter: {} over {} repeats takes the feature budget of {} under 1", feature_jitter,
                       repeats, budget);
  }
  if (budget + highest_shift * static_cast<long long>(feature_jitter) > std::numeric_limits<int>::max()) {
    return fmt::format("feature_jitter: {} over {} repeats takes the feature budget of {} past {}", feature_jitter,
                       repeats, budget, std::numeric_limits<int>::max());
  }
  return "";
}

int BenchSettings::FeatureBudgetShift(int repeat) { return repeat % 2 == 1 ? (repeat + 1) / 2 : -(repeat / 2); }

int BenchSettings::FeatureBudgetFor(int repeat) const {
  return TrackerOverrides().orb.max_features + FeatureBudgetShift(repeat) * feature_jitter;
}

std::vector<std::string> BenchSettings::TrackerAssignmentsFor(int repeat) const {
  std::vector<std::string> assignments = tracker;
  // Last, so that it overrides a budget set in `tracker`, from which it is counted.
  if (feature_jitter > 0) assignments.push_back(fmt::format("orb.max_features={}", FeatureBudgetFor(repeat)));
  return assignments;
}

slam::TrackerOptions BenchSettings::TrackerOverrides() const {
  slam::TrackerOptions options;
  for (const std::string& assignment : tracker) slam::SetTrackerOption(&options, assignment);
  return options;
}

seg::RefinerOptions BenchSettings::LoopRefinerOptions() const {
  seg::RefinerOptions options;
  for (const std::string& assignment : refiner) seg::SetRefinerOption(&options, assignment);
  return options;
}

std::string BenchSettings::SegmenterLabel() const {
  return segmenter == "gt" ? segmenter : SimulatedSegmenterLabel(segmenter, segmenter_strength);
}

RunConfig BenchSettings::RunConfigFor(const std::string& mode, std::uint64_t run_seed) const {
  const bool simulated = segmenter != "gt" && mode != "plain" && mode != "oracle";
  return MakeRunConfig("bench", mode, "gt", simulated ? segmenter : "", run_seed,
                       simulated ? segmenter_strength : 1.0);
}

}  // namespace segslam::harness
