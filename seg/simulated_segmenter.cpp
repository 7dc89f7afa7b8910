#include "seg/simulated_segmenter.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "core/coco.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/tracks.h"
#include "seg/mask_damage_internal.h"

namespace segslam::seg {
namespace {

namespace fs = std::filesystem;
using namespace mask_damage;

float Clamp01(double v, double lo = 0.0) {
  return static_cast<float>(std::clamp(v, lo, 1.0));
}

// ---------------------------------------------------------------------------------------
// The simulation of one frame: each ground-truth instance through the error modes
// (seg/mask_damage_internal.h), then false positives.

// The network's output for one ground-truth instance, or nothing when it is missed.
std::optional<InstanceMask> SimulateInstance(const SimulatedSegmenterOptions& o,
                                             std::uint64_t seed, int frame_index,
                                             const cv::Mat& gt_ids, const GtInstance& gt,
                                             const InstanceInfo& info,
                                             const SimulatedInstanceContext& ctx,
                                             const CategoriesInView& in_view) {
  const double image_area = static_cast<double>(gt_ids.total());
  // Persistent difficulty of this instance (the same in every frame).
  Rng difficulty_rng(seed, -1, gt.id, kStreamDifficulty);
  const double difficulty = o.difficulty_sd * difficulty_rng.Normal() +
                            (IsHardCategory(info.category_id) ? o.hard_category_difficulty : 0.0);

  // Missed? A fresh draw per frame: flicker.
  if (gt.area < o.min_area_px) return std::nullopt;
  Rng miss_rng(seed, frame_index, gt.id, kStreamMiss);
  if (miss_rng.Bernoulli(MissProbability(o, gt, ctx, difficulty, image_area))) {
    return std::nullopt;
  }

  // Work in the bounding box grown by the largest outward change.
  const ErrorReach reach(o, std::sqrt(static_cast<double>(gt.area)), std::exp(0.5 * difficulty));
  const int pad = reach.Padding();
  const cv::Rect box = cv::Rect(gt.x0 - pad, gt.y0 - pad, gt.x1 - gt.x0 + 1 + 2 * pad,
                                gt.y1 - gt.y0 + 1 + 2 * pad) &
                       cv::Rect(0, 0, gt_ids.cols, gt_ids.rows);
  cv::Mat truth;
  cv::compare(gt_ids(box), gt.id, truth, cv::CMP_EQ);
  truth /= 255;
  cv::Mat mask = truth.clone();
  const cv::Rect object_box(gt.x0 - box.x, gt.y0 - box.y, gt.x1 - gt.x0 + 1, gt.y1 - gt.y0 + 1);

  // The mask head's fixed resolution, then each kind of error from its own stream.
  if (o.mask_resolution > 0) CoarsenToGrid(object_box, o.mask_resolution, &mask);
  Rng holes_rng(seed, frame_index, gt.id, kStreamHoles);
  PunchHoles(o, reach, truth, gt.area, &holes_rng, &mask);
  Rng cut_rng(seed, frame_index, gt.id, kStreamCut);
  CutOffSide(o, reach, object_box, &cut_rng, &mask);
  Rng bleed_rng(seed, frame_index, gt.id, kStreamBleed);
  BleedOutward(o, reach, truth, gt.area, &bleed_rng, &mask);
  Rng neighbour_rng(seed, frame_index, gt.id, kStreamNeighbourBleed);
  BleedIntoNeighbours(o, reach, gt_ids(box), gt.id, truth, &neighbour_rng, &mask);
  Rng jitter_rng(seed, frame_index, gt.id, kStreamJitter);
  JitterBoundary(&jitter_rng, reach.jitter_px, reach.jitter_scale_px, &mask);

  const int produced = cv::countNonZero(mask);
  if (produced == 0) return std::nullopt;
  const int intersection = cv::countNonZero(mask & truth);
  const double iou = intersection / static_cast<double>(gt.area + produced - intersection);

  InstanceMask out;
  out.category_id = OutputCategory(o, seed, frame_index, gt.id, info.category_id, in_view);
  // The score follows the mask's quality; a confused class scores lower.
  Rng score_rng(seed, frame_index, gt.id, kStreamScore);
  double score = 1.0 - o.score_iou_weight * (1.0 - iou) + o.score_noise_sd * score_rng.Normal();
  if (out.category_id != info.category_id) score *= o.confusion_score_factor;
  out.score = Clamp01(score, 0.01);
  out.mask = cv::Mat::zeros(gt_ids.size(), CV_8U);
  mask.copyTo(out.mask(box));
  out.bounds = box;
  return out;
}

// False positives: blobs on the background, mostly low-scored, each like an object in
// view: the class and (scaled) size of a random ground-truth instance of the frame, else
// of a random class of the sequence at the size range.
std::vector<InstanceMask> SimulateFalsePositives(const SimulatedSegmenterOptions& o,
                                                 std::uint64_t seed, int frame_index,
                                                 const cv::Mat& gt_ids,
                                                 const std::vector<GtInstance>& frame_instances,
                                                 const InstanceTable& table) {
  std::vector<InstanceMask> blobs;
  Rng rng(seed, frame_index, 0, kStreamFalsePositives);
  const int count = rng.Poisson(o.false_positives_per_frame);
  if (count == 0) return blobs;
  const cv::Size size = gt_ids.size();
  const double image_area = static_cast<double>(size.area());
  const std::vector<int> sequence_categories = SequenceCategories(table);
  cv::Mat background;
  cv::compare(gt_ids, 0, background, cv::CMP_EQ);
  background /= 255;
  for (int k = 0; k < count; ++k) {
    int category = 0;
    double area = 0;
    if (!frame_instances.empty()) {
      const GtInstance& like =
          frame_instances[rng.UniformInt(0, static_cast<int>(frame_instances.size()) - 1)];
      category = table.Find(like.id)->category_id;
      area = std::clamp(like.area * std::exp(rng.Uniform(std::log(0.3), std::log(2.0))),
                        o.false_positive_area_min * image_area,
                        o.false_positive_area_max * image_area);
    } else {
      category = sequence_categories[rng.UniformInt(
          0, static_cast<int>(sequence_categories.size()) - 1)];
      area = image_area * std::exp(rng.Uniform(std::log(o.false_positive_area_min),
                                               std::log(o.false_positive_area_max)));
    }
    const double aspect = std::exp(rng.Uniform(std::log(0.4), std::log(2.5)));
    const int a = std::max(1, static_cast<int>(std::lround(std::sqrt(area * aspect / M_PI))));
    const int b = std::max(1, static_cast<int>(std::lround(std::sqrt(area / aspect / M_PI))));
    const cv::Point centre(rng.UniformInt(0, size.width - 1), rng.UniformInt(0, size.height - 1));
    const double angle = rng.Uniform(0, 180);
    const double score = rng.Uniform(0.01, o.false_positive_score_max);
    cv::Mat blob = cv::Mat::zeros(size, CV_8U);
    cv::ellipse(blob, centre, cv::Size(a, b), angle, 0, 360, 1, cv::FILLED);
    const double sqrt_area = std::sqrt(area);
    JitterBoundary(&rng, std::min(o.boundary_jitter_px, o.boundary_jitter_fraction * sqrt_area),
                   std::max(2.0, o.boundary_jitter_scale_fraction * sqrt_area), &blob);
    blob &= background;
    if (cv::countNonZero(blob) < std::max(20, o.min_area_px)) continue;
    InstanceMask out;
    out.category_id = category;
    out.score = Clamp01(score, 0.01);
    out.mask = std::move(blob);
    FitBounds(&out);
    blobs.push_back(std::move(out));
  }
  return blobs;
}

}  // namespace

SimulatedFrame SimulateSegmentation(const SimulatedSegmenterOptions& options, std::uint64_t seed,
                                    int frame_index, const cv::Mat& gt_ids,
                                    const InstanceTable& table,
                                    const std::map<std::uint16_t, SimulatedInstanceContext>& context) {
  std::string error;
  if (!options.IsValid(&error)) throw Error(error);
  if (gt_ids.type() != CV_16U) {
    throw Error("simulated segmenter: ground-truth ids must be CV_16UC1, got " +
                CvTypeName(gt_ids.type()));
  }
  const SimulatedSegmenterOptions o = options.Effective();

  std::vector<InstanceMask> outputs;
  std::vector<std::uint16_t> sources;  // ground-truth id of each output; 0: a false positive
  const std::vector<GtInstance> frame_instances = AnalyseIds(gt_ids);
  const CategoriesInView in_view = CountCategoriesInView(frame_instances, table);
  for (const GtInstance& gt : frame_instances) {
    const InstanceInfo* info = table.Find(gt.id);
    if (info == nullptr) {
      throw Error(fmt::format("simulated segmenter: frame {}: id {} is not in the instance table",
                              frame_index, gt.id));
    }
    const auto found = context.find(gt.id);
    const SimulatedInstanceContext ctx =
        found == context.end() ? SimulatedInstanceContext{} : found->second;
    std::optional<InstanceMask> out =
        SimulateInstance(o, seed, frame_index, gt_ids, gt, *info, ctx, in_view);
    if (!out) continue;
    outputs.push_back(std::move(*out));
    sources.push_back(gt.id);
  }
  for (InstanceMask& blob :
       SimulateFalsePositives(o, seed, frame_index, gt_ids, frame_instances, table)) {
    outputs.push_back(std::move(blob));
    sources.push_back(0);
  }

  // Number the outputs 1..N in a seeded per-frame order, so ids carry no ground truth.
  std::vector<size_t> order(outputs.size());
  std::iota(order.begin(), order.end(), 0);
  Rng order_rng(seed, frame_index, 0, kStreamOrder);
  for (size_t i = order.size(); i > 1; --i) {
    std::swap(order[i - 1], order[static_cast<size_t>(order_rng.UniformInt(0, static_cast<int>(i) - 1))]);
  }
  SimulatedFrame result;
  result.segmentation.frame_index = frame_index;
  for (size_t rank = 0; rank < order.size(); ++rank) {
    InstanceMask& out = outputs[order[rank]];
    out.track_id = static_cast<std::uint16_t>(rank + 1);
    result.segmentation.instances.push_back(std::move(out));
    result.gt_ids.push_back(sources[order[rank]]);
  }
  return result;
}

double OwnImageSpeedPxPerS(const Eigen::Isometry3d& T_wc, const PinholeCamera& camera,
                           const TrackSample& now, const TrackSample& next) {
  const double dt = next.stamp_s - now.stamp_s;
  if (!(dt > 0)) return -1.0;
  const Eigen::Isometry3d T_cw = T_wc.inverse();
  const Eigen::Vector3d a = T_cw * now.T_world_object.translation();
  const Eigen::Vector3d b = T_cw * next.T_world_object.translation();
  constexpr double kMinDepthM = 0.1;
  if (a.z() < kMinDepthM || b.z() < kMinDepthM) return -1.0;
  const Eigen::Vector2d shift(camera.fx * (b.x() / b.z() - a.x() / a.z()),
                              camera.fy * (b.y() / b.z() - a.y() / a.z()));
  return shift.norm() / dt;
}

// ---------------------------------------------------------------------------------------
// The segmenter over a sequence directory.

namespace {

// The ground-truth pose whose stamp is nearest to `stamp_s` and within `tolerance_s` of
// it, or nullptr (generated sequences write one pose per frame, at the frame's stamp).
const StampedPose* NearestPose(const std::vector<StampedPose>& poses, double stamp_s,
                               double tolerance_s) {
  auto after = std::lower_bound(poses.begin(), poses.end(), stamp_s,
                                [](const StampedPose& p, double stamp) { return p.stamp_s < stamp; });
  const StampedPose* best = nullptr;
  if (after != poses.end()) best = &*after;
  if (after != poses.begin() &&
      (best == nullptr || stamp_s - std::prev(after)->stamp_s < best->stamp_s - stamp_s)) {
    best = &*std::prev(after);
  }
  return best != nullptr && std::abs(best->stamp_s - stamp_s) <= tolerance_s ? best : nullptr;
}

}  // namespace

SimulatedSegmenter::SimulatedSegmenter(const fs::path& sequence_dir,
                                       const SimulatedSegmenterOptions& options,
                                       std::uint64_t seed, std::string preset_name)
    : dir_(sequence_dir), options_(options), seed_(seed), preset_name_(std::move(preset_name)) {
  std::string error;
  if (!options_.IsValid(&error)) throw Error(error);
  sequence_ = TumSequence::Open(dir_);
  if (!fs::is_directory(dir_ / "masks")) {
    throw FileError(dir_ / "masks", "no ground-truth masks folder (the simulated segmenter needs "
                                    "a generated sequence)");
  }
  table_ = InstanceTable::Read(dir_ / "instances.json");
  if (fs::exists(dir_ / "tracks.json")) {
    for (const ObjectTrack& track : ReadTracks(dir_ / "tracks.json")) {
      auto& states = tracks_[track.instance_id];
      for (size_t k = 0; k < track.samples.size(); ++k) {
        const TrackSample& s = track.samples[k];
        TrackState& state = states[s.frame];
        state.visible_pixels = s.visible_pixels;
        state.moving = s.moving;
        // "moving" means since the previous frame: the speed over the same step (the
        // first sample has none: the step after it).
        if (!s.moving || track.samples.size() < 2) continue;
        const size_t from = std::max<size_t>(k, 1) - 1;
        const TrackSample& a = track.samples[from];
        const TrackSample& b = track.samples[from + 1];
        const StampedPose* pose =
            NearestPose(sequence_.groundtruth(), a.stamp_s, 0.5 * (b.stamp_s - a.stamp_s));
        if (pose != nullptr) {
          state.own_image_speed_px_s =
              OwnImageSpeedPxPerS(pose->T_wc, sequence_.camera().intrinsics, a, b);
        }
      }
    }
  }
}

fs::path SimulatedSegmenter::MaskPath(size_t i) const {
  if (i >= sequence_.size()) {
    throw FileError(dir_, fmt::format("frame {} is out of range (the sequence has {} frames)", i,
                                      sequence_.size()));
  }
  return dir_ / "masks" / (sequence_.FrameStem(i) + ".png");
}

SimulatedFrame SimulatedSegmenter::SegmentWithTruth(const RgbdFrame& frame) {
  if (frame.index < 0) throw FileError(dir_, fmt::format("negative frame index {}", frame.index));
  const fs::path path = MaskPath(static_cast<size_t>(frame.index));
  if (!fs::exists(path)) throw FileError(path, "ground-truth mask is missing");
  // As stored: a network segments the stored image; its masks are then read into the
  // frame's geometry, as external masks are.
  const cv::Mat ids = ReadInstanceMask(path);
  const cv::Size expected = !frame.color_bgr.empty()
                                ? frame.color_bgr.size()
                                : cv::Size(sequence_.camera().intrinsics.width,
                                           sequence_.camera().intrinsics.height);
  if (ids.size() != expected) {
    throw FileError(path, fmt::format("mask is {}x{}, the frame is {}x{}", ids.cols, ids.rows,
                                      expected.width, expected.height));
  }
  CheckMaskIds(ids, table_, path.string());

  // Context from tracks.json: visible share against the recent maximum, and motion.
  std::map<std::uint16_t, SimulatedInstanceContext> context;
  for (const auto& [id, samples] : tracks_) {
    const auto here = samples.find(frame.index);
    if (here == samples.end()) continue;
    int recent_max = 0;
    for (auto it = samples.lower_bound(frame.index - options_.occlusion_window);
         it != samples.end() && it->first <= frame.index + options_.occlusion_window; ++it) {
      recent_max = std::max(recent_max, it->second.visible_pixels);
    }
    SimulatedInstanceContext ctx;
    ctx.visible_share =
        recent_max > 0 ? here->second.visible_pixels / static_cast<double>(recent_max) : 1.0;
    ctx.moving = here->second.moving;
    ctx.own_image_speed_px_s = here->second.own_image_speed_px_s;
    context[id] = ctx;
  }
  SimulatedFrame simulated = SimulateSegmentation(options_, seed_, frame.index, ids, table_, context);
  if (sequence_.camera().distortion.IsZero()) return simulated;
  SimulatedFrame loaded;
  loaded.segmentation.frame_index = simulated.segmentation.frame_index;
  for (size_t k = 0; k < simulated.segmentation.instances.size(); ++k) {
    InstanceMask& instance = simulated.segmentation.instances[k];
    instance.mask = sequence_.InstanceMaskAsLoaded(instance.mask);
    FitBounds(&instance);
    // Gone in the resampling: a sliver, or (barrel lens) all of it outside the pinhole frame.
    if (instance.bounds.empty()) continue;
    loaded.segmentation.instances.push_back(std::move(instance));
    loaded.gt_ids.push_back(simulated.gt_ids[k]);
  }
  return loaded;
}

FrameSegmentation SimulatedSegmenter::Segment(const RgbdFrame& frame) {
  return SegmentWithTruth(frame).segmentation;
}

std::string SimulatedSegmenter::name() const {
  std::string n = "simulated:" + preset_name_;
  if (options_.strength != 1.0) n += fmt::format("@{}", options_.strength);
  return n;
}

}  // namespace segslam::seg