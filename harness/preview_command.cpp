// `segslam preview DATASET/passN --frames 0,30,59 --out sheet.png`: a contact sheet of
// generated frames for a person to look at: colour | depth (colour-mapped) | instance
// overlay, one row per frame.
#include "core/error.h"
#include "core/image_io.h"
#include "core/atomic_file.h"
#include "core/tum_dataset.h"
#include "harness/cli_numbers.h"
#include "harness/commands.h"
#include "harness/pictures.h"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <memory>

namespace segslam::harness {
namespace {

struct PreviewArgs {
  std::string sequence_dir;
  std::vector<int> frames{0};
  std::string out_file;
  double max_depth_m = 0;  // 0 = the 98th percentile of the first frame
  std::string camera_file;  // for the depth scale of a sequence without camera.yaml
  std::string masks_dir;    // external masks (<stem>.png) instead of the sequence's masks/
};

int RunPreview(const PreviewArgs& args) {
  namespace fs = std::filesystem;
  const TumSequence sequence = TumSequence::OpenWithCameraFile(args.sequence_dir, args.camera_file);
  std::vector<cv::Mat> rows;
  double max_depth_m = args.max_depth_m;
  for (int index : args.frames) {
    if (index < 0 || static_cast<size_t>(index) >= sequence.size()) {
      throw Error(fmt::format("{}: frame {} out of range (0..{})", args.sequence_dir, index,
                              sequence.size() - 1));
    }
    const RgbdFrame frame = sequence.LoadFrame(index);
    if (max_depth_m <= 0) {
      std::vector<float> valid;
      for (auto it = frame.depth_m.begin<float>(); it != frame.depth_m.end<float>(); ++it) {
        if (*it > 0) valid.push_back(*it);
      }
      std::sort(valid.begin(), valid.end());
      max_depth_m = valid.empty() ? 1.0 : valid[valid.size() * 98 / 100];
    }
    const fs::path rgb_file = sequence.entries()[index].rgb_file;
    const fs::path mask_file = args.masks_dir.empty()
                                   ? fs::path(args.sequence_dir) / "masks" / rgb_file.filename()
                                   : fs::path(args.masks_dir) / (rgb_file.stem().string() + ".png");
    if (!args.masks_dir.empty() && !fs::exists(mask_file)) {
      throw FileError(mask_file, fmt::format("missing: the mask of frame {} ({})", index, rgb_file.string()));
    }
    cv::Mat overlay = fs::exists(mask_file)
                          ? OverlayPicture(frame.color_bgr, sequence.LoadInstanceMask(mask_file))
                          : frame.color_bgr.clone();
    rows.push_back(CaptionedRow(
        {frame.color_bgr, DepthPicture(frame.depth_m, max_depth_m), overlay},
        {fmt::format("frame {}  t={:.3f} s", index, frame.stamp_s),
         fmt::format("depth 0..{:.1f} m", max_depth_m),
         args.masks_dir.empty() ? std::string("instances") : "instances: " + fs::path(args.masks_dir).filename().string()}));
  }
  cv::Mat sheet;
  cv::vconcat(rows, sheet);
  WriteImageAtomically(args.out_file, sheet);
  fmt::print("wrote {} ({} frames: colour | depth | instances)\n", args.out_file, rows.size());
  return 0;
}

}  // namespace

void AddPreviewCommand(CLI::App& app, std::function<int()>* action) {
  auto args = std::make_shared<PreviewArgs>();
  CLI::App* command = app.add_subcommand(
      "preview", "Write a contact sheet of a sequence's frames: colour | depth | instance overlay");
  command->add_option("sequence", args->sequence_dir, "A TUM-layout sequence, e.g. data/city/pass1")
      ->required();
  command->add_option("--frames", args->frames, "Frame indices, e.g. 0,30,59")
      ->delimiter(',')
      ->check(WholeNumberIn(0, kMaxFrames));
  command->add_option("--out,-o", args->out_file, "Output PNG")->required();
  command->add_option("--max-depth", args->max_depth_m, "Depth colour scale in metres (0 = auto)")
      ->check(NumberIn(0, 1e6));
  command->add_option("--camera", args->camera_file,
                      "camera.yaml to use instead of the sequence's own (its depth_factor scales the depth "
                      "of a real sequence without one)");
  command->add_option("--masks", args->masks_dir,
                      "A folder of external masks (<stem>.png, e.g. from `masks import` or a run's refined_masks/) "
                      "to overlay instead of the sequence's own masks/");
  command->callback([args, action] { *action = [args] { return RunPreview(*args); }; });
}

}  // namespace segslam::harness
