// `segslam bench aliasing DATASET`: perceptual aliasing per pass (harness/aliasing.h):
// among pairs of frames that share no static view, the most ORB matches that survive a
// ratio test and RANSAC PnP, and their distribution. Also the summary that `generate`
// records in manifest.json.
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/tum_dataset.h"
#include "harness/aliasing.h"
#include "harness/aliasing_report.h"
#include "harness/cli_numbers.h"
#include "harness/commands.h"
#include "harness/interrupt.h"
#include "harness/progress_bar.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <memory>

namespace segslam::harness {

namespace fs = std::filesystem;

namespace {

struct BenchAliasingArgs {
  std::string dataset;
  std::string json_file;
  std::string pictures_dir;
  std::string camera_file;
  AliasingOptions options;  // the measure's options, set by the options of the same names
};

int RunBenchAliasing(const BenchAliasingArgs& args) {
  AliasingOptions options = args.options;
  options.cancel = InstallInterruptFlag();
  if (std::string problem; !options.IsValid(&problem)) throw Error("bench aliasing: " + problem);
  if (!fs::is_directory(args.dataset)) throw FileError(args.dataset, "not a folder");

  const auto start = std::chrono::steady_clock::now();
  const auto passes = MeasureAliasingOfFolder(options, args.dataset, args.camera_file, true);
  fmt::print("aliasing of {}: a frame every {} m or {} deg of ground-truth motion{}, all pairs of them; pairs with no "
             "common view (under {} % of either frame's background points seen by the other) or {} m apart or more, "
             "matched with {} ORB features{}, ratio {}, RANSAC PnP ({} samples, {} px), counted at a pose more than {} m "
             "from the truth; a loop detector accepts about {} verified matches\n",
             args.dataset, options.sample_spacing_m, options.sample_turn_deg,
             options.sample_every_frames > 0 ? fmt::format(" or {} frames", options.sample_every_frames) : "",
             100.0 * options.common_view.min_common_share, options.common_view.far_apart_m, options.orb.max_features,
             options.background_features_only ? " (on background where there are masks)"
                                              : " (a match within one instance not counted)", options.ratio, options.ransac_samples,
             options.ransac_max_error_px, options.true_place_tolerance_m, kLoopAcceptanceMatches);
  fmt::print("{}", AliasingTable(passes));

  if (!args.pictures_dir.empty()) {
    fs::create_directories(args.pictures_dir);
    for (const auto& [name, summary] : passes) {
      if (summary.worst_pairs.empty() || summary.max_verified_matches == 0) continue;
      const fs::path folder = AliasingSequences(args.dataset).size() == 1 ? fs::path(args.dataset)
                                                                          : fs::path(args.dataset) / name;
      const TumSequence sequence = TumSequence::OpenWithCameraFile(folder, args.camera_file);
      const fs::path png = fs::path(args.pictures_dir) / (name + "_worst_pair.png");
      WriteColorImage(png, AliasingPairPicture(options, sequence, summary.worst_pairs.front()));
      fmt::print("{}: worst pair drawn in {}\n", name, png.string());
    }
  }
  if (!args.json_file.empty()) {
    nlohmann::json json = {{"dataset", args.dataset}, {"settings", options.ToJson()}};
    for (const auto& [name, summary] : passes) json["passes"][name] = summary.ToJson();
    WriteFileAtomically(args.json_file, json.dump(2) + "\n");
  }
  // Time on stderr: stdout and the JSON stay the same bytes for the same input.
  fmt::print(stderr, "measured in {:.1f} s\n",
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return 0;
}

}  // namespace

void AddBenchAliasingCommand(CLI::App& bench, std::function<int()>* action) {
  auto args = std::make_shared<BenchAliasingArgs>();
  CLI::App* command = bench.add_subcommand(
      "aliasing",
      "Perceptual aliasing: among pairs of frames that share no static view (ground truth), the most ORB matches "
      "that survive a ratio test and RANSAC PnP, per pass (docs/aliasing.md)");
  command->add_option("dataset", args->dataset, "A dataset (with pass1/, pass2/) or one TUM-layout sequence with "
                                                "groundtruth.txt")
      ->required();
  command->add_option("--spacing", args->options.sample_spacing_m, "Sample a frame every this many metres of ground-truth travel")
      ->check(NumberIn(0, 1e6, /*min_excluded=*/true))
      ->capture_default_str();
  command->add_option("--turn", args->options.sample_turn_deg, "... or every this many degrees of turn")
      ->check(NumberIn(0, 360, /*min_excluded=*/true))
      ->capture_default_str();
  command->add_option("--every", args->options.sample_every_frames, "... or every this many frames (0 = never)")
      ->check(WholeNumberIn(0, kMaxFrames, "0 = never"))
      ->capture_default_str();
  command->add_option("--ransac-samples", args->options.ransac_samples,
                      "RANSAC PnP samples per pair (ORB-SLAM2's loop closing: 300; relocalization here: 2000)")
      ->check(WholeNumberIn(1, 1000000))
      ->capture_default_str();
  command->add_option("--far-apart", args->options.common_view.far_apart_m,
                      "Also measure pairs whose cameras are at least this many metres apart, whatever they share far "
                      "off (0: only pairs with no common view)")
      ->check(NumberIn(0, 1e6))
      ->capture_default_str();
  command->add_option("--min-common-share", args->options.common_view.min_common_share,
                      "Pairs with a smaller share of either frame's background points seen by the other share no "
                      "view")
      ->check(NumberIn(1e-6, 0.999999))
      ->capture_default_str();
  command->add_flag("--background-only", args->options.background_features_only,
                    "Match features on ground-truth background only (default: every feature; a match between two "
                    "features on the same instance, the same object at both places, is not counted)");
  command->add_option("--threads", args->options.threads, "Worker threads (0 = all cores)")
      ->check(WholeNumberIn(0, kMaxThreads, "0 = all cores"));
  command->add_option("--json", args->json_file, "Also write the results as JSON");
  command->add_option("--pictures", args->pictures_dir,
                      "Draw each pass's worst pair with its verified matches into DIR/<pass>_worst_pair.png");
  command->add_option("--camera", args->camera_file,
                      "camera.yaml to use instead of the sequence's own (for a real sequence without one)");
  command->callback([args, action] { *action = [args] { return RunBenchAliasing(*args); }; });
}

}  // namespace segslam::harness
