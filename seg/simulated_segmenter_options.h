// The simulated segmenter's options (seg/simulated_segmenter.h): every error rate and
// magnitude, the named presets, and setting fields by name for tuning and sweeps.
#pragma once

#include <string>
#include <vector>

namespace segslam::seg {

// Every error rate and magnitude of the simulated segmenter. Probabilities are per
// instance and frame unless said otherwise. `strength` scales all of them (see
// Effective()); the defaults are the "fcis-like" preset.
struct SimulatedSegmenterOptions {
  // Scales every probability and magnitude below: 0 = ground truth, 1 = as written,
  // > 1 worse (probabilities are clamped to 1). Range [0, 10].
  double strength = 1.0;

  // --- Missed instances (false negatives) ---
  // Probability of missing any instance, [0, 1].
  double miss_prob = 0.02;
  // Extra miss probability of an instance of area -> 0, falling linearly to 0 at
  // `small_area_fraction` of the image area, [0, 1].
  double miss_small_prob = 0.05;
  // Area (share of the image's pixels) below which an instance counts as small, [0, 1].
  double small_area_fraction = 0.002;
  // Instances with fewer visible pixels than this are never detected, pixels, >= 0.
  int min_area_px = 3;
  // Extra miss probability of an instance fully truncated by the image border
  // (border pixels >= sqrt(area)); scales linearly with the truncation, [0, 1].
  double miss_truncated_prob = 0.6;
  // The truncation's extra miss probability fades linearly to 0 as the visible area
  // grows to this share of the image: a person a metre from the lens, cut at the waist
  // by the border, is still found (FCIS and Mask R-CNN find TUM's walkers), [0, 1].
  double truncated_large_area_fraction = 0.08;
  // Extra miss probability of a fully occluded instance; scales linearly with
  // 1 - visible share (visible pixels over their maximum within +-`occlusion_window`
  // frames, from tracks.json), [0, 1].
  double miss_occluded_prob = 0.2;
  // Frames on each side over which the visible maximum is taken, >= 0. Short, so that
  // objects growing as the camera approaches do not count as occluded.
  int occlusion_window = 5;
  // Extra miss probability of a moving instance (tracks.json "moving"): motion blur. It
  // scales with the instance's own image motion (its pose change between this frame and
  // the next, projected with the camera held still), reaching the full rate at
  // `moving_full_miss_speed_px_s`: a walker a metre or two from a hand-held Kinect is
  // blurred over many pixels, a pedestrian 15 m down a street hardly at all. Where the
  // speed is unknown (no ground-truth pose, origin behind the camera) the full rate, [0, 1].
  double miss_moving_prob = 0.3;
  // Own image speed (pixels per second) at which a moving instance is missed at the full
  // `miss_moving_prob` (250: a walker at 0.8 m/s, 1.7 m from a 525-px Kinect), > 0.
  double moving_full_miss_speed_px_s = 250.0;
  // Standard deviation of an instance's persistent difficulty, added to the logit of its
  // miss probability and scaling its shape errors by exp(difficulty / 2), >= 0.
  double difficulty_sd = 0.3;
  // Difficulty added to every instance of the COCO categories that mask networks segment
  // worst (per-category COCO mask AP of Mask R-CNN-class models roughly 0.1-0.25 against
  // ~0.35 on average: bench, chair, potted plant, dining table, book; thin legs, open
  // shapes, cluttered tops), >= 0.
  double hard_category_difficulty = 1.5;

  // --- Missing parts ---
  // Probability that holes are punched into a detected instance, [0, 1].
  double hole_prob = 0.15;
  // Largest number of holes (uniform in 1..max), >= 1.
  int hole_count_max = 3;
  // Hole radius as a share of sqrt(instance area), uniform up to this, [0, 1].
  double hole_radius_fraction = 0.18;
  // Probability that one side of the instance is cut off, [0, 1].
  double cut_prob = 0.12;
  // Largest share of the bounding box (along a random axis, from a random side) that a
  // cut removes, [0, 1).
  double cut_fraction_max = 0.35;

  // --- Oversized regions ---
  // Probability that the region bleeds outward (dilated, into background or neighbours), [0, 1].
  double bleed_prob = 0.25;
  // Largest bleed width as a share of sqrt(instance area), uniform up to this, [0, 1].
  double bleed_fraction_max = 0.1;
  // Probability that a bleeding region also grows a blob on one side (bleeding into the
  // background or a neighbour over a longer stretch), [0, 1].
  double bleed_blob_prob = 0.3;

  // Probability that the region also spreads into the instances it touches, which the
  // mask head cannot tell apart from it (FCIS's artifacts on overlapping instances): the
  // pixels of other instances within the reach below, painted as this one, [0, 1].
  // Off in fcis-like: the paper's refinement cannot undo it (a spread region projected
  // forward spreads again; docs/segmentation.md); on in "poor", and a knob for stress tests.
  double neighbour_bleed_prob = 0.0;
  // Largest reach into touching instances as a share of sqrt(instance area), uniform
  // from a third of it up to it, [0, 1].
  double neighbour_bleed_fraction_max = 0.15;

  // --- Boundaries ---
  // Side of the fixed grid on which the mask head predicts each instance inside its box
  // (FCIS: 21, Mask R-CNN: 28); the mask is averaged onto that grid, resized back
  // bilinearly and thresholded at one half, so that detail finer than a grid cell (a
  // walker's limbs, a table's legs, the gap between a monitor and its stand) is lost on
  // instances larger than the grid and kept on small ones. 0 = off; strength divides it
  // (coarser), >= 0. Off in fcis-like (it costs thin objects, chairs above all, more AP
  // than the paper's FCIS shows; docs/segmentation.md); on in "poor".
  int mask_resolution = 0;
  // Amplitude of the smooth random boundary displacement, as a share of sqrt(instance
  // area) (mask heads work at a fixed resolution per box, so their boundary error grows
  // with the object), [0, 1] ...
  double boundary_jitter_fraction = 0.01;
  // ... and at most this many pixels, >= 0.
  double boundary_jitter_px = 12.0;
  // Spatial scale of the boundary jitter (noise grid spacing) as a share of sqrt(instance
  // area), at least 2 pixels, (0, 10].
  double boundary_jitter_scale_fraction = 0.3;

  // --- Classes ---
  // Probability of reporting a similar COCO class instead of the true one (only for
  // classes with look-alikes: car/truck/bus, bicycle/motorcycle, cup/bottle/wine glass/
  // vase/bowl, chair/couch/bench, tv/laptop, cat/dog, ...) that is in view in the same
  // frame (a network mistakes a car for the truck parked nearby; a confusion into a class
  // absent from the scene would only add a zero class to mIoU), [0, 1]. The rate is for a
  // look-alike with at least as many pixels in view; towards a rarer look-alike it falls
  // with 2 * other / (own + other) pixels (networks lean towards the common class).
  double confusion_prob = 0.01;
  // (The wrong class is drawn per instance, not per frame: confused again with the same
  // look-alikes in view, an instance is confused the same way.)

  // --- False positives ---
  // Expected false positives per frame (Poisson), >= 0. Each is a jittered ellipse on the
  // background (no ground-truth overlap) looking like an object in view: the class of a
  // random ground-truth instance of the frame and 0.3 to 2 times its area (a random class
  // of the sequence if the frame has none).
  double false_positives_per_frame = 4.0;
  // False-positive area range (clamps the area above), share of the image's pixels,
  // 0 < min <= max <= 1.
  double false_positive_area_min = 0.0002;
  double false_positive_area_max = 0.15;

  // --- Scores ---
  // A true detection scores clamp(1 - score_iou_weight * (1 - IoU) + N(0, score_noise_sd),
  // 0.01, 1), IoU of the produced mask with its ground-truth instance, times
  // `confusion_score_factor` if its class is wrong. Clean output scores 1.
  double score_iou_weight = 1.0;          // Not scaled by strength, [0, 5].
  double score_noise_sd = 0.05;           // >= 0.
  double confusion_score_factor = 0.75;   // (0, 1]; strength moves it away from 1.
  // False positives score uniformly in [0.01, false_positive_score_max], [0.01, 1];
  // not scaled by strength.
  double false_positive_score_max = 0.6;

  // The named presets: "clean" (ground truth, every error off), "fcis-like" (the
  // defaults, tuned towards the paper's FCIS: mAP 0.63-0.67 and mIoU 0.56-0.65; the
  // figures per shipped scenario and which options move them: docs/segmentation.md),
  // "mask-rcnn-like" (fewer and smaller errors), "poor" (a weak network). Throws
  // segslam::Error listing them on another name.
  static SimulatedSegmenterOptions Preset(const std::string& name);
  static std::vector<std::string> PresetNames();

  // Sets the field `name` (as spelled in this struct, e.g. "miss_truncated_prob") from
  // "name=value", for tuning and sweeps (seg-eval --segmenter-option). Integer fields
  // take whole numbers only. Throws segslam::Error naming the field on an unknown name or
  // a value that is not a number; ranges are checked later by IsValid().
  void Set(const std::string& assignment);
  static std::vector<std::string> FieldNames();

  // The options with `strength` applied: rates and magnitudes multiplied by it
  // (probabilities clamped to 1), strength set to 1. Strength 0 gives clean output.
  SimulatedSegmenterOptions Effective() const;

  // False (and a message naming the field and its range) if any field is out of range.
  bool IsValid(std::string* error) const;
};

}  // namespace segslam::seg
