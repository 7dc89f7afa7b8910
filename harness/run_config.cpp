#include "harness/run_config.h"

#include <fmt/format.h>

#include "core/error.h"
#include "core/strings.h"
#include "seg/simulated_segmenter_options.h"

namespace segslam::harness {

std::string MaskSource::Describe() const {
  switch (kind) {
    case Kind::kNone: return "none";
    case Kind::kGroundTruth: return "gt";
    case Kind::kExternal: return "external " + folder.string();
    case Kind::kSimulated: {
      std::string label = fmt::format("simulated {} seed {}", SimulatedSegmenterLabel(preset, strength), seed);
      if (!overrides.empty()) label += " [" + Join(overrides, ", ") + "]";
      return label;
    }
  }
  return "?";
}

seg::SimulatedSegmenterOptions SimulatedSegmenterOptionsFor(const std::string& preset, double strength,
                                                            const std::vector<std::string>& overrides) {
  seg::SimulatedSegmenterOptions options = seg::SimulatedSegmenterOptions::Preset(preset);
  options.strength = strength;
  for (const std::string& assignment : overrides) options.Set(assignment);
  return options;
}

seg::SimulatedSegmenterOptions MaskSource::SimulatedOptions() const {
  const seg::SimulatedSegmenterOptions options = SimulatedSegmenterOptionsFor(preset, strength, overrides);
  if (std::string problem; !options.IsValid(&problem)) throw Error("simulated segmenter: " + problem);
  return options;
}

RunConfig RunConfigWords::ToConfig(const std::string& command) const {
  RunConfig config = MakeRunConfig(command, mode, masks, segmenter, seed, strength);
  if (segmenter_options.empty()) return config;
  if (segmenter.empty()) {
    throw Error(command + ": --segmenter-option sets a simulated segmenter's option: give --segmenter too");
  }
  if (config.masks.kind != MaskSource::Kind::kSimulated) return config;  // plain reads no masks
  config.masks.overrides = segmenter_options;
  try {
    config.masks.SimulatedOptions();
  } catch (const Error& e) {
    throw Error(command + ": --segmenter-option: " + e.what());
  }
  return config;
}

bool RunConfig::RefinesMasks() const {
  return mutual::IsMutualLoop(mode) &&
         (masks.kind == MaskSource::Kind::kExternal || masks.kind == MaskSource::Kind::kSimulated);
}

bool RunConfig::IsDeterministic() const { return masks.kind != MaskSource::Kind::kSimulated; }

std::string SimulatedSegmenterLabel(const std::string& preset, double strength) {
  return strength == 1.0 ? preset : fmt::format("{}@{}", preset, strength);
}

std::string PresetWithOverrides(const std::string& preset, const std::vector<std::string>& overrides) {
  return overrides.empty() ? preset : preset + "[" + Join(overrides, ",") + "]";
}

RunConfig MakeRunConfig(const std::string& command, const std::string& mode, const std::string& masks,
                        const std::string& segmenter, std::uint64_t seed, double strength) {
  const std::string where = command + ": ";
  RunConfig config;
  try {
    config.mode = mutual::ParseSlamMode(mode);
  } catch (const Error& e) {
    throw Error(where + e.what());
  }
  if (!(strength >= 0 && strength <= 10)) {
    throw Error(where + fmt::format("--strength must be in [0, 10] (got {})", strength));
  }
  if (!segmenter.empty() && !Contains(seg::SimulatedSegmenterOptions::PresetNames(), segmenter)) {
    throw Error(where + "unknown segmenter '" + PrintableText(segmenter) + "' (" +
                Join(seg::SimulatedSegmenterOptions::PresetNames(), ", ") + ")");
  }
  if (!segmenter.empty() && masks != "gt") {
    throw Error(where + "--segmenter " + segmenter + " and --masks " + PrintableText(masks) +
                " exclude each other (the simulated segmenter degrades the ground-truth masks)");
  }
  if (strength != 1.0 && segmenter.empty()) {
    throw Error(where + "--strength scales the simulated segmenter's errors: give --segmenter too");
  }
  if (config.mode == mutual::SlamMode::kOracle && (!segmenter.empty() || masks != "gt")) {
    throw Error(where + "mode oracle takes the dataset's ground-truth masks and tracks (the verdicts a perfect "
                        "judgement would give): no --segmenter or --masks DIR");
  }
  if (!mutual::UsesMasks(config.mode)) {
    config.masks.kind = MaskSource::Kind::kNone;
  } else if (!segmenter.empty()) {
    config.masks.kind = MaskSource::Kind::kSimulated;
    config.masks.preset = segmenter;
    config.masks.seed = seed;
    config.masks.strength = strength;
  } else if (masks != "gt") {
    config.masks.kind = MaskSource::Kind::kExternal;
    config.masks.folder = masks;
  }
  return config;
}

}  // namespace segslam::harness
