// A simulated instance segmenter for synthetic sequences: it starts from the ground-truth
// instance masks and degrades them with the error modes that real networks (FCIS, Mask
// R-CNN) show and that the paper's refinement (section III.D) exists to repair:
//   - missed instances, more often when small, truncated at the image border, occluded
//     or moving (motion blur), and flickering from frame to frame;
//   - missing parts: holes and a cut-off side;
//   - oversized regions that bleed into the background or a neighbour;
//   - jittered boundaries;
//   - class confusions among similar COCO classes (car/truck/bus, cup/bottle, ...);
//   - false positives, mostly low-scored;
// with scores that grow with the produced mask's quality (its IoU with the ground truth),
// so that AP ranks detections meaningfully.
//
// Determinism: every random draw comes from a generator seeded by (seed, frame index,
// ground-truth instance id, error mode), never from call order: a frame gives the same
// result whatever frames were segmented before. Each instance also has a persistent
// difficulty (seeded by (seed, instance id) only), so some instances are hard throughout.
//
// Images: ground-truth ids CV_16U (0 = background); output masks CV_8U 0/1 (segmentation.h).
// Options and presets: seg/simulated_segmenter_options.h; the error modes themselves:
// seg/mask_damage_internal.h.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "core/instances.h"
#include "core/tracks.h"
#include "core/tum_dataset.h"
#include "seg/segmenter.h"
#include "seg/simulated_segmenter_options.h"

namespace segslam::seg {


// What the simulator knows of a ground-truth instance in a frame besides its mask.
struct SimulatedInstanceContext {
  double visible_share = 1.0;  // Visible pixels over their recent maximum, [0, 1].
  bool moving = false;         // The object moves in this frame.
  // Image speed of the object's own motion, pixels per second; < 0 = unknown.
  double own_image_speed_px_s = -1.0;
};

// Image speed, pixels per second, of an object's own motion from track sample `now` to
// `next`: both of its positions projected by `camera` held still at `T_wc` (its pose at
// `now`), so the camera's own motion does not count. -1 (unknown) if `next` is not later
// or either position is less than 0.1 m in front of the camera.
double OwnImageSpeedPxPerS(const Eigen::Isometry3d& T_wc, const PinholeCamera& camera,
                           const TrackSample& now, const TrackSample& next);

// A simulated segmentation and, for debugging and tests, where each output came from.
struct SimulatedFrame {
  FrameSegmentation segmentation;
  // Per output instance (same order): its ground-truth instance id, 0 for a false positive.
  std::vector<std::uint16_t> gt_ids;
};

// Degrades the ground truth `gt_ids` (CV_16U, 0 = background, ids from `table`) of the
// frame `frame_index` as `options` say (strength applied here). Instances missing from
// `context` get the default context. Deterministic in (options, seed, frame_index, the
// inputs). Output track ids are a seeded per-frame permutation of 1..N (not the GT ids).
// Throws segslam::Error on invalid options, a non-CV_16U image or an id not in `table`.
SimulatedFrame SimulateSegmentation(const SimulatedSegmenterOptions& options, std::uint64_t seed,
                                    int frame_index, const cv::Mat& gt_ids,
                                    const InstanceTable& table,
                                    const std::map<std::uint16_t, SimulatedInstanceContext>& context);

// The simulated segmenter over a generated sequence directory (one pass of a segslam
// dataset): reads <dir>/instances.json, <dir>/tracks.json (optional: without it nothing
// counts as occluded or moving) and, per frame, <dir>/masks/<stem of the rgb file>.png.
// Not copyable.
class SimulatedSegmenter : public Segmenter {
 public:
  // Opens the sequence (TumSequence::Open) and reads its tables. Throws segslam::Error on
  // invalid options (naming the field), a missing masks/ folder or instances.json, or
  // any reader's error.
  SimulatedSegmenter(const std::filesystem::path& sequence_dir,
                     const SimulatedSegmenterOptions& options, std::uint64_t seed,
                     std::string preset_name = "fcis-like");
  SimulatedSegmenter(const SimulatedSegmenter&) = delete;
  SimulatedSegmenter& operator=(const SimulatedSegmenter&) = delete;

  // Reads frame.index's ground-truth mask and degrades it. With a distorted camera it
  // degrades the mask as stored, as a network segments the stored image (an object cut
  // by the image border is truncated there, not where the undistorted frame ends), and
  // returns the masks undistorted, in the frame's geometry. Throws segslam::Error naming
  // the mask file if it is missing, not 16-bit, of another size than the frame, or holds
  // an id not in instances.json, or if frame.index is out of range.
  FrameSegmentation Segment(const RgbdFrame& frame) override;
  // As Segment(), with the ground-truth id of every output instance.
  SimulatedFrame SegmentWithTruth(const RgbdFrame& frame);

  // "simulated:<preset>" plus "@<strength>" when the strength is not 1.
  std::string name() const override;

  const SimulatedSegmenterOptions& options() const { return options_; }
  // The ground-truth mask file of frame i.
  std::filesystem::path MaskPath(size_t i) const;

 private:
  std::filesystem::path dir_;
  SimulatedSegmenterOptions options_;
  std::uint64_t seed_;
  std::string preset_name_;
  TumSequence sequence_;
  InstanceTable table_;
  // What tracks.json says of an instance in a frame.
  struct TrackState {
    int visible_pixels = 0;
    bool moving = false;
    double own_image_speed_px_s = -1.0;  // < 0 = unknown
  };
  // Per instance id: frame -> state.
  std::map<std::uint16_t, std::map<int, TrackState>> tracks_;
};

}  // namespace segslam::seg
