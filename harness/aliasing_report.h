// The aliasing measure (harness/aliasing.h) as the commands report it: per pass of a
// dataset, as a table for people, and as the summary `generate` records in manifest.json.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/aliasing.h"

namespace segslam::harness {

// generate's sampling, coarser than bench aliasing's so that the measure adds about a
// tenth to a city's generation time (docs/aliasing.md has the figures).
constexpr double kManifestSampleSpacingM = 4.0;
constexpr double kManifestSampleTurnDeg = 30.0;
constexpr int kManifestSampleEveryFrames = 60;

// The sequences of `dir` by name: pass1/ and pass2/ of a dataset (those present), else
// `dir` itself, named after its folder.
std::vector<std::pair<std::string, std::filesystem::path>> AliasingSequences(const std::filesystem::path& dir);

// Every sequence of `dir` measured (AliasingSequences), with a progress bar on stderr
// when `show_progress`. `camera_yaml`: as TumSequence::OpenWithCameraFile. Throws as
// MeasureAliasing and TumSequence::Open do.
std::vector<std::pair<std::string, AliasingSummary>> MeasureAliasingOfFolder(const AliasingOptions& options,
                                                                             const std::filesystem::path& dir,
                                                                             const std::string& camera_yaml,
                                                                             bool show_progress);

// AliasingOptions with generate's coarser sampling.
AliasingOptions ManifestAliasingOptions();

// {"settings": ..., "passes": {"pass1": {"sampled_frames", "pairs_no_common_view",
// "max_verified_matches", "pairs_at_or_above_20", "worst_pair": {...}}, ...}}: no times,
// so the same dataset gives the same manifest.
nlohmann::json ManifestAliasingSummary(const AliasingOptions& options,
                                       const std::vector<std::pair<std::string, AliasingSummary>>& passes);

// One line per pass: frames, sampled, pairs, pairs with no common view, p50/p90/p99, max,
// pairs at or above kLoopAcceptanceMatches, and the worst pair.
std::string AliasingTable(const std::vector<std::pair<std::string, AliasingSummary>>& passes);

}  // namespace segslam::harness
