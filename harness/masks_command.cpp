// `segslam masks images SEQUENCE --out images.json` and
// `segslam masks import SEQUENCE DETECTIONS.json --out MASKS`: the bridge between an
// instance segmentation network and the core. The first lists the sequence's colour
// images as a COCO dataset (to register with detectron2, MMDetection, ...); the second
// turns the network's COCO detections (seg/coco_detections.h) into the external-mask
// folder that `run --masks` and `seg-eval --masks` read (seg/external_masks.h).
#include "core/atomic_file.h"
#include "core/coco.h"
#include "core/error.h"
#include "core/tum_dataset.h"
#include "harness/commands.h"
#include "harness/interrupt.h"
#include "harness/progress_bar.h"
#include "seg/coco_detections.h"
#include "seg/external_masks.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <chrono>
#include <filesystem>
#include <memory>
#include <set>

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;

struct MasksImagesArgs {
  std::string sequence_dir;
  std::string camera_file;
  std::string out_file;
};

struct MasksImportArgs {
  std::string sequence_dir;
  std::string detections_file;
  std::string images_file;
  std::string camera_file;
  std::string out_dir;
  double min_score = seg::CocoImportOptions().min_score;
  bool force = false;
  bool quiet = false;
};

// Image ids are 1-based frame numbers, in the sequence's frame order.
int RunMasksImages(const MasksImagesArgs& args) {
  const TumSequence sequence = TumSequence::OpenWithCameraFile(args.sequence_dir, args.camera_file);
  const PinholeCamera& camera = sequence.camera().intrinsics;
  nlohmann::json images = nlohmann::json::array();
  for (size_t i = 0; i < sequence.size(); ++i) {
    const TumFrameEntry& entry = sequence.entries()[i];
    images.push_back({{"id", i + 1},
                      {"file_name", entry.rgb_file},
                      {"width", camera.width},
                      {"height", camera.height},
                      {"timestamp", entry.rgb_stamp_s}});
  }
  nlohmann::json categories = nlohmann::json::array();
  for (const CocoCategory& category : CocoCategories()) {
    categories.push_back({{"id", category.id},
                          {"name", std::string(category.name)},
                          {"supercategory", std::string(category.supercategory)}});
  }
  const nlohmann::json dataset = {
      {"info", {{"description", "colour images of " + sequence.dir().string() + " (file names relative to it)"}}},
      {"images", images},
      {"annotations", nlohmann::json::array()},
      {"categories", categories}};
  WriteFileAtomically(args.out_file, dataset.dump(1) + "\n");
  fmt::print("wrote {}: {} images of {}, the 80 COCO categories\n", args.out_file, sequence.size(),
             sequence.dir().string());
  return 0;
}

int RunMasksImport(const MasksImportArgs& args) {
  const TumSequence sequence = TumSequence::OpenWithCameraFile(args.sequence_dir, args.camera_file);
  seg::CocoImportOptions options;
  options.min_score = args.min_score;
  options.images_file = args.images_file;
  const seg::CocoDetections detections = seg::CocoDetections::Read(args.detections_file, sequence, options);

  StagingDirectory staging(args.out_dir, args.force);
  const cv::Size size(sequence.camera().intrinsics.width, sequence.camera().intrinsics.height);
  ProgressBar bar("masks import " + fs::path(args.sequence_dir).filename().string());
  const auto start = std::chrono::steady_clock::now();
  const std::atomic<bool>* cancel = InstallInterruptFlag();
  int hidden = 0;  // kept detections that higher-scoring ones cover entirely
  const int total = static_cast<int>(sequence.size());
  for (size_t i = 0; i < sequence.size(); ++i) {
    if (cancel->load()) throw Error("masks import: cancelled; nothing was written to " + args.out_dir);
    const seg::FrameSegmentation masks = detections.Frame(i);
    const cv::Mat ids = masks.ToIdImage(size);
    std::set<std::uint16_t> visible(ids.begin<std::uint16_t>(), ids.end<std::uint16_t>());
    for (const seg::InstanceMask& instance : masks.instances) hidden += visible.count(instance.track_id) == 0;
    seg::WriteExternalMaskFiles(staging.path(), fs::path(sequence.entries()[i].rgb_file).stem().string(), ids,
                                masks);
    if (!args.quiet) {
      const int done = static_cast<int>(i) + 1;
      const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      bar.Update(done, total, done / std::max(elapsed_s, 1e-9));
    }
  }
  if (!args.quiet) bar.Finish();
  staging.Commit();

  const seg::CocoImportCounts& counts = detections.counts();
  fmt::print("{:<38} {:>8}\n", "detections in " + fs::path(args.detections_file).filename().string(),
             counts.detections);
  fmt::print("{:<38} {:>8}\n", "  on images of other sequences", counts.other_images);
  fmt::print("{:<38} {:>8}\n", "  crowd regions (skipped)", counts.crowd);
  fmt::print("{:<38} {:>8}\n", fmt::format("  scoring below {:g}", args.min_score), counts.below_min_score);
  fmt::print("{:<38} {:>8}\n", "  kept", counts.kept);
  fmt::print("{:<38} {:>8}\n", "    of them hidden by higher scores", hidden);
  fmt::print("{:<38} {:>8}\n", "frames with a kept detection", fmt::format("{} of {}", counts.frames_with_detections,
                                                                           sequence.size()));
  std::string classes;
  for (const auto& [category_id, count] : counts.kept_per_category) {
    classes += fmt::format("{}{} {}", classes.empty() ? "" : ", ", FindCocoCategory(category_id)->name, count);
  }
  if (!classes.empty()) fmt::print("kept per class: {}\n", classes);
  fmt::print("wrote {} (<stem>.png and <stem>.json per frame; `segslam run {} --masks {}`)\n", args.out_dir,
             args.sequence_dir, args.out_dir);
  return 0;
}

}  // namespace

void AddMasksCommand(CLI::App& app, std::function<int()>* action) {
  CLI::App* masks = app.add_subcommand(
      "masks", "Bring an instance segmentation network's output to a sequence: its image list as a COCO dataset, "
               "and its COCO detections as external masks");
  masks->require_subcommand(1);

  auto images_args = std::make_shared<MasksImagesArgs>();
  CLI::App* images = masks->add_subcommand(
      "images", "Write the sequence's colour images as a COCO dataset file (ids 1, 2, ... in frame order, the 80 "
                "COCO categories, no annotations) to run a network on");
  images->add_option("sequence", images_args->sequence_dir, "A TUM-layout sequence")->required();
  images->add_option("--out,-o", images_args->out_file, "Output JSON file")->required();
  images->add_option("--camera", images_args->camera_file,
                     "camera.yaml to use instead of the sequence's own (a real sequence without one)");
  images->callback([images_args, action] { *action = [images_args] { return RunMasksImages(*images_args); }; });

  auto import_args = std::make_shared<MasksImportArgs>();
  CLI::App* import = masks->add_subcommand(
      "import", "Turn a network's COCO detections (results list or dataset file; RLE or polygons) into the "
                "external-mask folder that run --masks reads");
  import->add_option("sequence", import_args->sequence_dir, "The TUM-layout sequence the network segmented")
      ->required();
  import->add_option("detections", import_args->detections_file,
                     "COCO results (list of image_id, category_id, segmentation, score) or a COCO dataset file")
      ->required();
  import->add_option("--out,-o", import_args->out_dir, "Output folder of masks")->required();
  import->add_option("--images", import_args->images_file,
                     "The COCO image list the network ran on, for integer image ids (e.g. from `masks images`)");
  import->add_option("--min-score", import_args->min_score, "Drop detections scoring lower")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  import->add_option("--camera", import_args->camera_file,
                     "camera.yaml to use instead of the sequence's own (a real sequence without one)");
  import->add_flag("--force", import_args->force, "Replace an existing output folder");
  import->add_flag("--quiet,-q", import_args->quiet, "No progress bar");
  import->callback([import_args, action] { *action = [import_args] { return RunMasksImport(*import_args); }; });
}

}  // namespace segslam::harness
