// `segslam masks images | import | export`: the bridge between instance segmentation
// networks and the core, in COCO's formats. `images` lists a sequence's colour images as a
// COCO dataset (to register with detectron2, MMDetection, ...); `import` turns a network's
// COCO detections (seg/coco_detections.h) into the external-mask folder that `run --masks`
// and `seg-eval --masks` read (seg/external_masks.h); `export` writes such a folder (a
// run's refined_masks/, say) or the simulated segmenter's output as COCO results, for
// COCO's own evaluation tools against a generated sequence's annotations_coco.json.
#include "core/atomic_file.h"
#include "core/coco.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/output_folders.h"
#include "core/tum_dataset.h"
#include "harness/cli_numbers.h"
#include "harness/commands.h"
#include "harness/interrupt.h"
#include "harness/progress_bar.h"
#include "seg/coco_detections.h"
#include "seg/external_masks.h"
#include "seg/simulated_segmenter.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <vector>

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

struct MasksExportArgs {
  std::string sequence_dir;
  std::string camera_file;
  std::string out_file;
  std::string masks_dir;
  std::string segmenter;
  std::uint64_t seed = 1;
  double strength = 1.0;
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
  nlohmann::json info = {{"description", "colour images of " + sequence.dir().string() + " (file names relative to it)"}};
  if (sequence.size() > 0) {
    // What tells this sequence from another with the same stamps (CocoDetections::Read).
    info["first_frame"] = sequence.entries().front().rgb_file;
    info["first_frame_sha256"] = sequence.FirstFrameSha256();
  }
  const nlohmann::json dataset = {
      {"info", info},
      {"images", images},
      {"annotations", nlohmann::json::array()},
      {"categories", categories}};
  WriteFileAtomically(args.out_file, dataset.dump(1) + "\n");
  fmt::print("wrote {}: {} images of {}, the 80 COCO categories\n", args.out_file, sequence.size(),
             sequence.dir().string());
  return 0;
}

// One instance per pixel, as the folder holds them: where masks overlap the higher score
// is on top (FrameSegmentation::ToIdImage); instances left without a pixel are dropped,
// the others numbered 1, 2, ... in their order. `masks`' track ids must be 1..n.
cv::Mat FlattenToIdImage(seg::FrameSegmentation* masks, cv::Size size) {
  const cv::Mat painted = masks->ToIdImage(size);
  std::vector<bool> visible(masks->instances.size() + 1, false);
  for (auto it = painted.begin<std::uint16_t>(); it != painted.end<std::uint16_t>(); ++it) visible[*it] = true;
  std::vector<std::uint16_t> renumbered(masks->instances.size() + 1, 0);
  std::vector<seg::InstanceMask> kept;
  for (seg::InstanceMask& instance : masks->instances) {
    if (!visible[instance.track_id]) continue;
    renumbered[instance.track_id] = static_cast<std::uint16_t>(kept.size() + 1);
    instance.track_id = renumbered[instance.track_id];
    kept.push_back(std::move(instance));
  }
  masks->instances = std::move(kept);
  cv::Mat ids(size, CV_16U);
  std::transform(painted.begin<std::uint16_t>(), painted.end<std::uint16_t>(), ids.begin<std::uint16_t>(),
                 [&](std::uint16_t id) { return renumbered[id]; });
  return ids;
}

int RunMasksImport(const MasksImportArgs& args) {
  const TumSequence sequence = TumSequence::OpenWithCameraFile(args.sequence_dir, args.camera_file);
  seg::CocoImportOptions options;
  options.min_score = args.min_score;
  options.images_file = args.images_file;
  const seg::CocoDetections detections = seg::CocoDetections::Read(args.detections_file, sequence, options);

  // --force replaces the output folder: never the sequence or what it is made of.
  const fs::path out = fs::weakly_canonical(args.out_dir);
  for (const char* part : {"", "masks", "rgb", "depth"}) {
    if (out == fs::weakly_canonical(sequence.dir() / part)) {
      throw FileError(args.out_dir, fmt::format("is the sequence's own {}; write the masks elsewhere",
                                                *part == '\0' ? std::string("folder") : std::string(part) + "/"));
    }
  }
  // --force replaces only a folder masks import wrote, never one that holds other files.
  StagingDirectory staging(args.out_dir, args.force, ForeignContentOfMaskFolder, "folder of masks");
  const cv::Size size(sequence.camera().intrinsics.width, sequence.camera().intrinsics.height);
  ProgressBar bar("masks import " + fs::path(args.sequence_dir).filename().string());
  const auto start = std::chrono::steady_clock::now();
  const std::atomic<bool>* cancel = InstallInterruptFlag();
  int hidden = 0;  // kept detections that higher-scoring ones cover entirely: left out
  const int total = static_cast<int>(sequence.size());
  for (size_t i = 0; i < sequence.size(); ++i) {
    if (cancel->load()) throw Error("masks import: cancelled; nothing was written to " + args.out_dir);
    seg::FrameSegmentation masks = detections.Frame(i);
    const size_t detected = masks.instances.size();
    const cv::Mat ids = FlattenToIdImage(&masks, size);
    hidden += static_cast<int>(detected - masks.instances.size());
    seg::WriteExternalMaskFiles(staging.path(), sequence.FrameStem(i), ids, masks);
    if (!args.quiet) {
      const int done = static_cast<int>(i) + 1;
      const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      bar.Update(done, total, done / std::max(elapsed_s, 1e-9));
    }
  }
  if (!args.quiet) bar.Finish();
  seg::WriteMaskFolderRecord(staging.path(), sequence);
  staging.Commit();

  const seg::CocoImportCounts& counts = detections.counts();
  fmt::print("{:<44} {:>8}\n", "detections in " + fs::path(args.detections_file).filename().string(),
             counts.detections);
  fmt::print("{:<44} {:>8}\n", "  on images of other sequences", counts.other_images);
  fmt::print("{:<44} {:>8}\n", "  crowd regions (skipped)", counts.crowd);
  fmt::print("{:<44} {:>8}\n", fmt::format("  scoring below {:g}", args.min_score), counts.below_min_score);
  fmt::print("{:<44} {:>8}\n", "  kept", counts.kept);
  fmt::print("{:<44} {:>8}\n", "    of them hidden by higher scores, left out", hidden);
  fmt::print("{:<44} {:>8}\n", "frames with a kept detection", fmt::format("{} of {}", counts.frames_with_detections,
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

// Image ids as `masks images` and a generated sequence's annotations_coco.json number them.
int RunMasksExport(const MasksExportArgs& args) {
  if (args.masks_dir.empty() == args.segmenter.empty()) {
    throw Error("masks export: give either --masks DIR or --segmenter PRESET");
  }
  const TumSequence sequence = TumSequence::OpenWithCameraFile(args.sequence_dir, args.camera_file);
  const cv::Size size(sequence.camera().intrinsics.width, sequence.camera().intrinsics.height);
  std::unique_ptr<seg::SimulatedSegmenter> simulated;
  std::unique_ptr<seg::ExternalMaskSegmenter> folder;  // checks that every frame's two files are there
  if (!args.segmenter.empty()) {
    seg::SimulatedSegmenterOptions options = seg::SimulatedSegmenterOptions::Preset(args.segmenter);
    options.strength = args.strength;
    simulated = std::make_unique<seg::SimulatedSegmenter>(sequence.dir(), options, args.seed, args.segmenter);
  } else {
    folder = std::make_unique<seg::ExternalMaskSegmenter>(args.masks_dir, sequence);
  }

  nlohmann::json results = nlohmann::json::array();
  std::map<int, int> per_category;
  ProgressBar bar("masks export " + fs::path(args.sequence_dir).filename().string());
  const auto start = std::chrono::steady_clock::now();
  const std::atomic<bool>* cancel = InstallInterruptFlag();
  const int total = static_cast<int>(sequence.size());
  for (size_t i = 0; i < sequence.size(); ++i) {
    if (cancel->load()) throw Error("masks export: cancelled; nothing was written to " + args.out_file);
    seg::FrameSegmentation masks;
    if (simulated != nullptr) {
      masks = simulated->Segment(sequence.LoadFrame(i));
      // A network segments the images as stored.
      for (seg::InstanceMask& instance : masks.instances) {
        instance.mask = sequence.InstanceMaskAsStored(instance.mask);
        seg::FitBounds(&instance);
      }
    } else {
      // Read as stored, without the undistortion a run applies.
      const fs::path png = folder->MaskPath(i), table = folder->TablePath(i);
      masks = seg::ExternalMasksToSegmentation(ReadInstanceMask(png),
                                               seg::ParseExternalMaskTable(ReadJsonFile(table), table.string()),
                                               size, static_cast<int>(i), png.string());
    }
    for (nlohmann::json& entry : seg::CocoResultsOfFrame(masks, static_cast<int>(i) + 1)) {
      ++per_category[entry.at("category_id").get<int>()];
      results.push_back(std::move(entry));
    }
    if (!args.quiet) {
      const int done = static_cast<int>(i) + 1;
      const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      bar.Update(done, total, done / std::max(elapsed_s, 1e-9));
    }
  }
  if (!args.quiet) bar.Finish();
  WriteFileAtomically(args.out_file, results.dump() + "\n");
  std::string classes;
  for (const auto& [category_id, count] : per_category) {
    classes += fmt::format("{}{} {}", classes.empty() ? "" : ", ", FindCocoCategory(category_id)->name, count);
  }
  fmt::print("wrote {}: {} detections on {} frames (image ids 1..{} in frame order){}{}\n", args.out_file,
             results.size(), sequence.size(), sequence.size(), classes.empty() ? "" : "; ", classes);
  return 0;
}

}  // namespace

void AddMasksCommand(CLI::App& app, std::function<int()>* action) {
  CLI::App* masks = app.add_subcommand(
      "masks", "Instance masks in COCO's formats: a sequence's image list for a network, the network's detections "
               "as external masks, masks as COCO results");
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
      ->check(NumberIn(0, 1))
      ->capture_default_str();
  import->add_option("--camera", import_args->camera_file,
                     "camera.yaml to use instead of the sequence's own (a real sequence without one)");
  import->add_flag("--force", import_args->force, "Replace an existing output folder");
  import->add_flag("--quiet,-q", import_args->quiet, "No progress bar");
  import->callback([import_args, action] { *action = [import_args] { return RunMasksImport(*import_args); }; });

  auto export_args = std::make_shared<MasksExportArgs>();
  CLI::App* exported = masks->add_subcommand(
      "export", "Write a folder of external masks (e.g. a run's refined_masks/) or the simulated segmenter's output "
                "as a COCO results file (image ids 1, 2, ... in frame order, as in annotations_coco.json)");
  exported->add_option("sequence", export_args->sequence_dir, "The TUM-layout sequence the masks belong to")
      ->required();
  exported->add_option("--out,-o", export_args->out_file, "Output JSON file")->required();
  exported->add_option("--masks", export_args->masks_dir, "A folder in the external-mask layout");
  exported->add_option("--segmenter", export_args->segmenter, "Simulated segmenter preset (a generated sequence)")
      ->check(CLI::IsMember(seg::SimulatedSegmenterOptions::PresetNames()));
  exported->add_option("--seed", export_args->seed, "Seed of the simulated segmenter")->capture_default_str();
  exported->add_option("--strength", export_args->strength, "Scale of the simulated segmenter's errors")
      ->check(NumberIn(0, 10))
      ->capture_default_str();
  exported->add_option("--camera", export_args->camera_file,
                       "camera.yaml to use instead of the sequence's own (a real sequence without one)");
  exported->add_flag("--quiet,-q", export_args->quiet, "No progress bar");
  exported->callback([export_args, action] { *action = [export_args] { return RunMasksExport(*export_args); }; });
}

}  // namespace segslam::harness
