// What one SLAM run is: its mode (mutual/slam_mode.h) and where its instance masks come
// from. A command builds it once, where its input arrives (the command line, a
// scenario's bench: settings), with MakeRunConfig, which holds every rule of which modes
// take which masks; everything below takes the typed config and asks it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "mutual/slam_mode.h"
#include "seg/simulated_segmenter_options.h"

namespace segslam::harness {

struct MaskSource {
  enum class Kind {
    kNone,         // plain mode reads no masks
    kGroundTruth,  // the dataset's masks/ with instances.json (seg::GroundTruthSegmenter)
    kExternal,     // a folder of an external segmenter's masks (seg/external_masks.h)
    kSimulated,    // the simulated segmenter on the ground truth (seg/simulated_segmenter.h)
  };
  Kind kind = Kind::kGroundTruth;
  std::filesystem::path folder;  // kExternal
  std::string preset;            // kSimulated: a SimulatedSegmenterOptions preset
  std::uint64_t seed = 1;        // kSimulated
  double strength = 1.0;         // kSimulated: scales every error (0 = ground truth, 2 = twice as bad)
  // kSimulated: fields of the preset set by name, "NAME=VALUE" (SimulatedSegmenterOptions::
  // Set), to tell which of the segmenter's errors a run's figures depend on.
  std::vector<std::string> overrides;

  // As trajectory headers and messages name it: "none", "gt", "external DIR",
  // "simulated fcis-like seed 1" (fcis-like@2 where the strength is 2; the overrides
  // follow in brackets: "simulated fcis-like seed 1 [hole_prob=0]").
  std::string Describe() const;
  // The simulated segmenter's options: the preset, its strength and the overrides.
  // Throws segslam::Error naming the field on an unknown one or a value out of range.
  seg::SimulatedSegmenterOptions SimulatedOptions() const;
};

struct RunConfig {
  mutual::SlamMode mode = mutual::SlamMode::kMutual;
  MaskSource masks;

  // The paper's loop refines the masks: mutual or mutual-sparse mode with a segmenter's
  // masks (simulated or external). The ground truth's have nothing to repair.
  bool RefinesMasks() const;
  // No seed matters: plain, the oracle, or ground-truth masks.
  bool IsDeterministic() const;
  std::string ModeName() const { return mutual::ToString(mode); }
};

// A simulated segmenter preset as reports name it: "fcis-like", or "fcis-like@2" when its
// errors are scaled (as SimulatedSegmenter::name() writes the strength).
std::string SimulatedSegmenterLabel(const std::string& preset, double strength);

// A simulated segmenter preset at `strength` with fields set by name ("NAME=VALUE",
// SimulatedSegmenterOptions::Set, which throws naming an unknown field); ranges are not
// checked here (SimulatedSegmenterOptions::IsValid).
seg::SimulatedSegmenterOptions SimulatedSegmenterOptionsFor(const std::string& preset, double strength,
                                                            const std::vector<std::string>& overrides);

// A simulated segmenter preset with fields set by name, as its masks' files name it
// (SimulatedSegmenter::name(), seg.json): "fcis-like", "fcis-like[hole_prob=0,cut_prob=0]".
std::string PresetWithOverrides(const std::string& preset, const std::vector<std::string>& overrides);

// The one check of a run's mode and masks, from a command's words: `masks` is "gt" or a
// folder of external masks, `segmenter` a simulated segmenter preset or empty. Plain reads
// no masks, so it gets MaskSource::kNone whatever was given. Throws segslam::Error
// starting with "`command`: " on an unknown mode or preset, a simulated segmenter
// together with external masks, the oracle with other masks than the ground truth's (its
// verdicts name the ground truth's instance ids), a strength outside [0, 10], or a
// strength other than 1 without a simulated segmenter.
RunConfig MakeRunConfig(const std::string& command, const std::string& mode, const std::string& masks,
                        const std::string& segmenter, std::uint64_t seed, double strength);

// The words of a command line that say a run's mode and masks (--mode, --masks,
// --segmenter, --seed, --strength, --segmenter-option), before MakeRunConfig checks them.
struct RunConfigWords {
  std::string mode = "mutual";
  std::string masks = "gt";
  std::string segmenter;
  std::uint64_t seed = 1;
  double strength = 1.0;
  std::vector<std::string> segmenter_options;  // NAME=VALUE, into MaskSource::overrides
  // MakeRunConfig, then the overrides: refused without a simulated segmenter, or where
  // one names no field or sets it out of range.
  RunConfig ToConfig(const std::string& command) const;
};

}  // namespace segslam::harness
