#include "harness/aliasing_report.h"

#include "harness/progress_bar.h"

#include <fmt/format.h>

#include <chrono>
#include <optional>

namespace segslam::harness {

namespace fs = std::filesystem;

std::vector<std::pair<std::string, fs::path>> AliasingSequences(const fs::path& dir) {
  std::vector<std::pair<std::string, fs::path>> sequences;
  for (const char* pass : {"pass1", "pass2"}) {
    if (fs::is_directory(dir / pass)) sequences.emplace_back(pass, dir / pass);
  }
  if (sequences.empty()) sequences.emplace_back(dir.filename().empty() ? dir.parent_path().filename().string()
                                                                       : dir.filename().string(),
                                                dir);
  return sequences;
}

AliasingOptions ManifestAliasingOptions() {
  AliasingOptions options;
  options.sample_spacing_m = kManifestSampleSpacingM;
  options.sample_turn_deg = kManifestSampleTurnDeg;
  options.sample_every_frames = kManifestSampleEveryFrames;
  return options;
}

nlohmann::json ManifestAliasingSummary(const AliasingOptions& options,
                                       const std::vector<std::pair<std::string, AliasingSummary>>& passes) {
  nlohmann::json json = {{"settings", options.ToJson()}};
  for (const auto& [name, summary] : passes) {
    nlohmann::json pass = {{"sampled_frames", summary.sampled_frames},
                           {"pairs_no_common_view", summary.pairs_no_common_view},
                           {"pairs_measured", summary.pairs_measured},
                           {"max_verified_matches", summary.max_verified_matches},
                           {fmt::format("pairs_at_or_above_{}", kLoopAcceptanceMatches),
                            summary.pairs_at_or_above_acceptance}};
    if (!summary.worst_pairs.empty()) {
      const AliasingPair& worst = summary.worst_pairs.front();
      pass["worst_pair"] = {{"frame_a", worst.frame_a}, {"frame_b", worst.frame_b}, {"distance_m", worst.distance_m}};
    }
    json["passes"][name] = pass;
  }
  return json;
}

std::string AliasingTable(const std::vector<std::pair<std::string, AliasingSummary>>& passes) {
  std::string table = fmt::format("{:<8} {:>7} {:>7} {:>9} {:>9} {:>9} {:>5} {:>5} {:>5} {:>5} {:>6}  {}\n", "pass",
                                  "frames", "sampled", "pairs", "no view", "measured", "p50", "p90", "p99", "max",
                                  fmt::format(">={}", kLoopAcceptanceMatches),
                                  "worst pair: frames, true distance, PnP pose error");
  for (const auto& [name, s] : passes) {
    std::string worst = "-";
    if (!s.worst_pairs.empty() && s.max_verified_matches > 0) {
      const AliasingPair& w = s.worst_pairs.front();
      worst = fmt::format("{}-{}, {:.1f} m apart, ", w.frame_a, w.frame_b, w.distance_m);
      worst += w.pose_error_m >= 0 ? fmt::format("pose {:.1f} m off", w.pose_error_m) : std::string("no pose");
    }
    table += fmt::format("{:<8} {:>7} {:>7} {:>9} {:>9} {:>9} {:>5} {:>5} {:>5} {:>5} {:>6}  {}\n", name, s.frames,
                         s.sampled_frames, s.pairs_tested, s.pairs_no_common_view, s.pairs_measured, s.p50, s.p90, s.p99,
                         s.max_verified_matches, s.pairs_at_or_above_acceptance, worst);
  }
  return table;
}

std::vector<std::pair<std::string, AliasingSummary>> MeasureAliasingOfFolder(const AliasingOptions& options,
                                                                             const fs::path& dir,
                                                                             const std::string& camera_yaml,
                                                                             bool show_progress) {
  std::vector<std::pair<std::string, AliasingSummary>> passes;
  for (const auto& [name, folder] : AliasingSequences(dir)) {
    const TumSequence sequence = TumSequence::OpenWithCameraFile(folder, camera_yaml);
    // One bar per stage (frames, then pairs), each with its own rate.
    std::optional<ProgressBar> bar;
    std::string bar_stage;
    auto stage_start = std::chrono::steady_clock::now();
    AliasingProgress progress;
    if (show_progress) {
      progress = [&, name = name](const std::string& stage, int done, int total) {
        if (!bar || stage != bar_stage) {
          if (bar) bar->Finish();
          bar.emplace("aliasing " + name, stage);
          bar_stage = stage;
          stage_start = std::chrono::steady_clock::now();
        }
        const double elapsed =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - stage_start).count();
        bar->Update(done, total, elapsed > 0 ? done / elapsed : 0.0);
      };
    }
    passes.emplace_back(name, MeasureAliasing(options, sequence, progress));
    if (bar) bar->Finish();
  }
  return passes;
}

}  // namespace segslam::harness
