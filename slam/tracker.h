// Instance-aware RGB-D tracking (paper section III.B-C on ORB-SLAM2's RGB-D design;
// DESIGN.md "The core", steps 1, 3, 4, 5).
//
// Per frame the mutual loop calls, in order:
//   BeginFrame(frame)               ORB features with depth
//   EstimateCoarsePose()            T_c(t) from all features (step 1)
//   JudgeInstances(instances)       split into A and B_i, moving/static per instance (step 3)
//   EstimateFinePose()              T_f(t) from A and the static B_s only (step 4)
//   UpdateMaps()                    keyframes, new points, local BA (step 5)
// Which calls a frame gets is the mode's choice: mutual/frame_pipeline.h makes it.
//
// Tracking (EstimateCoarsePose): constant-velocity prediction and projection matching
// against the last frame, else descriptor matching against the reference keyframe with
// RANSAC PnP, then projection matching against the local map (every map point whose
// frustum, scale range, viewing angle and depth-occlusion test admit it), each followed
// by robust pose optimisation (slam/pose_optimizer.h). When that fails the frame is lost
// and the tracker relocalizes against all map points (descriptor search, through an LSH
// index for a loaded map's, slam/descriptor_index.h; RANSAC PnP); a
// young map that stays lost is dropped and begun anew (TrackerOptions::reset_map_keyframes).
//
// Localization (the paper's second pass): LoadLongTermMap() makes the loaded points
// fixed; the first frame is relocalized against them, tracking matches them like any
// point, and new points go to the tracking map only (see slam/map.h).
//
// Everything runs on the calling thread, so results are deterministic; local bundle
// adjustment runs inside UpdateMaps() and is timed separately.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

#include "core/camera.h"
#include "core/frame.h"
#include "slam/bundle_adjustment.h"
#include "slam/map.h"
#include "slam/map_file.h"
#include "slam/orb_extractor.h"
#include "slam/pose_optimizer.h"

namespace segslam::slam {

enum class TrackingStatus { kTracking, kRelocalized, kLost };
std::string ToString(TrackingStatus status);

// Instance masks of one frame as slam/ needs them: ids per pixel and which ids are of a
// moveable class. (slam/ does not depend on seg/; mutual/ converts.)
struct FrameInstances {
  cv::Mat ids;                                   // CV_16U, frame-sized, 0 = background
  std::unordered_set<std::uint16_t> moveable_ids;
};

struct InstanceJudgement {
  std::uint16_t id = 0;
  bool moveable_class = false;
  bool judged = false;          // enough evidence (TrackerOptions::min_points_to_judge;
                                // from depth: log-odds of moving not 0)
  bool moving = false;
  int num_features = 0;         // features of this instance in the frame
  // Measurements of its motion: features (the judgement from sparse features), or depth
  // samples landing on valid depth in the other frame (from depth), and how many of them
  // moved or were contradicted.
  int num_points = 0;
  int num_moving_points = 0;
  double moving_share = 0;      // num_moving_points / num_points
};

// What became of one feature of a frame (TrackerOptions::record_features), for pictures
// such as the paper's Fig. 6 and for counting where features went.
enum class FeatureKind : std::uint8_t {
  kUsed,             // matched to a map point and an inlier of the frame's last pose optimisation
  kUnmatched,        // no map point matched it (it may seed a new point)
  kOutlier,          // matched, but the robust pose optimisation rejected the match
  kDroppedMoving,    // on an instance judged moving (mutual): kept out of the fine pose
  kDroppedMoveable,  // on a moveable-class instance: removed before tracking (mask-moveable),
                     // or not judged yet (mutual)
};
std::string ToString(FeatureKind kind);

struct FeatureRecord {
  cv::Point2f pixel;              // keypoint position (u, v) in level-0 pixels
  // Instance under the keypoint as the step that used masks saw it: 0 = background, or no
  // mask consulted (plain mode; features kept by mask-moveable).
  std::uint16_t instance_id = 0;
  FeatureKind kind = FeatureKind::kUnmatched;
  int level = 0;  // pyramid level the keypoint was found at
};

struct FrameTimings {
  double features_ms = 0;
  double coarse_ms = 0;
  double judge_ms = 0;
  double fine_ms = 0;
  double map_update_ms = 0;     // keyframe decision, new points, culling (no BA)
  double bundle_adjustment_ms = 0;
  double TrackingMs() const { return features_ms + coarse_ms + judge_ms + fine_ms + map_update_ms; }
};

struct FrameResult {
  int frame_index = 0;
  double stamp_s = 0;
  TrackingStatus status = TrackingStatus::kLost;
  Eigen::Isometry3d T_wc_coarse = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();  // fine; meaningless if lost
  int num_features = 0;
  int num_features_with_depth = 0;
  int num_coarse_inliers = 0;
  int num_fine_inliers = 0;
  // Localization mode (a long-term map loaded): the fine pose's inliers on the loaded
  // map's points; -1 when no map was loaded.
  int num_long_term_inliers = -1;
  // Tracked, and in localization mode matched to the long-term map (at least
  // TrackerOptions::min_long_term_inliers of them). A frame tracked on the points it made
  // itself is tracked but not localized on the map: the paper's pass-2 figure counts
  // these, and a relocalization at a look-alike place 100 m off then shows as what it is.
  bool on_long_term_map = false;
  bool keyframe = false;
  // The map was dropped at this (lost) frame, to begin anew (TrackerOptions::
  // reset_map_keyframes): the poses of the frames before it are in a frame that no longer
  // exists, and a caller keeping them should count those frames lost.
  bool map_reset = false;
  // The frame was tracked a second time, from the pass's start, with verdicts given in
  // hindsight (TrackerOptions::retrack_map_start); this is the second result.
  bool retracked = false;
  std::vector<InstanceJudgement> instances;
  FrameTimings timings;
  bool localized() const { return status != TrackingStatus::kLost; }
  bool localized_on_map() const { return localized() && (num_long_term_inliers < 0 || on_long_term_map); }
  // One record per extracted feature (num_features of them), filled by EstimateFinePose()
  // only when TrackerOptions::record_features is set.
  std::vector<FeatureRecord> feature_records;
};

// The judgement from depth (TrackerOptions::judge_by_depth): every instance's depth
// pixels, carried by the background's motion into a frame motion_baseline_s back and
// compared with the depth measured there, both ways; the verdicts accumulate along the
// instance's track id as a log-odds of moving (slam/depth_judgement.cpp).
struct DepthJudgementOptions {
  // Interior pixels of an instance sampled per frame (on a grid as fine as this allows).
  int samples_per_instance = 200;
  // A sample's mask and depth must agree this many pixels around it: on a silhouette the
  // depth reads either side of the edge, and a small pose error moves it across.
  int interior_margin_px = 2;
  // A frame measures an instance on at least this many samples that land on valid depth.
  int min_samples = 12;
  // Samples are taken, and compared, only up to this depth: beyond, the depth noise of a
  // still object contradicts about as many samples as a moving one's motion (a city
  // sensor's 0.3 mm at 1 m, growing with depth squared, is 1 m at 50 m, as much as a
  // walker moves in a second). No map point is made that far either (max_point_depth_m).
  double max_depth_m = 40.0;
  // Also ask the instance's re-found sparse features where depth did not see it move:
  // they see a flat face sliding within its own plane, which depth cannot (without them a
  // box filling half the view and sliding sideways is taken for still and drags the
  // pose, TrackerTest.ObjectFillingTheViewThatStartsToMoveIsJudgedMovingAndLeftOutOfThePose).
  // They also see still cars a few metres away move for a frame or two (docs/tuning.md).
  bool sparse_features = true;
  // A frame sees the instance move when at least this share of its measured samples is
  // contradicted (the depth there lies beyond moving_distance_m + moving_distance_per_m
  // * depth): a car moving along its length vacates only its ends, and the depth noise
  // of a still one at 40 m contradicts a few in ten.
  double moving_share = 0.25;
  // Log-odds of moving: a frame that sees the instance move raises them to at least
  // moving_log_odds (a still past does not outweigh it), one that sees it still over a
  // full baseline takes static_log_odds, both within +-max_log_odds. An instance is
  // moving while they are above 0, still below 0, not yet judged at 0. Seen moving for
  // long, it needs max_log_odds / static_log_odds frames seen still to enter the pose
  // and map again.
  double moving_log_odds = 1.0;
  double static_log_odds = 0.5;
  double max_log_odds = 3.0;
};

struct TrackerOptions {
  OrbExtractorOptions orb;
  // Depth noise at 1 m in metres (> 0; grows with depth squared). Depth enters the
  // optimisation as ORB-SLAM2's "virtual stereo" coordinate u_r = u - bf / depth with
  // bf = 1 / depth_sigma_at_1m, so depth is weighed as the sensor measures it (Kinect:
  // about 1.5 mm at 1 m); ORB-SLAM2's fixed baseline trusts it ~15 times less.
  double depth_sigma_at_1m = 0.0015;
  // Points are created only up to this depth; farther depth is too noisy to map.
  float max_point_depth_m = 40.0f;
  // Matching: Hamming distance limits (of 256 bits) and the nearest/second ratio.
  int max_descriptor_distance = 100;
  int strict_descriptor_distance = 50;
  float projection_ratio = 0.8f;
  float relocalization_ratio = 0.8f;
  // Projection search radii in pixels at pyramid level 0.
  double last_frame_radius_px = 7;
  double local_map_radius_px = 3;
  // A tracked frame needs this many inliers after local-map tracking (more right after a
  // relocalization, as ORB-SLAM, so a wrong relocalization does not stick).
  int min_tracking_inliers = 30;
  int min_relocalization_inliers = 50;
  // Look-alike guard: a relocalization also solves for a rival pose on the matches the
  // first pose's consensus left out (at least min_rival_consensus of them agreeing;
  // a huge value turns the guard off), and tracks both on the local map. When they lie
  // more than rival_pose_distance_m apart and the weaker has at least
  // rival_support_ratio (0..1) of the stronger's local-map inliers, the frame stays
  // lost: two places that explain the view about as well are not a relocalization
  // (figures: docs/tuning.md, "The tracker").
  int min_rival_consensus = 10;
  double rival_pose_distance_m = 2.0;
  double rival_support_ratio = 0.4;
  // RANSAC PnP of a relocalization: at most this many minimal samples of four matches
  // (AP3P, >= 1), stopping sooner once a consensus is found with 99 % confidence. Across
  // a whole map as few as a fifth of the matches can be right, and a consensus of 20 %
  // is drawn in 2000 samples with probability 0.96 (docs/tuning.md, "The tracker").
  int relocalization_ransac_iterations = 2000;
  // Localization mode: a frame with fewer fine-pose inliers on the long-term map's points
  // than this is off the map (ORB-SLAM2's localization mode counts 10), tracked only on
  // the points it made itself, which drift or may sit in the frame of a wrong
  // relocalization. While off the map the tracker (with relocalize_off_map) tries to
  // relocalize on the long-term map, at most once an off_map_relocalization_interval_s
  // (a search over the whole map: 0.6 s on a city route's), and takes the pose it finds,
  // as ORB-SLAM2 does each frame; the points made since it left the map are dropped then,
  // as they are in the frame it has just found to be wrong.
  int min_long_term_inliers = 10;
  bool relocalize_off_map = true;
  double off_map_relocalization_interval_s = 0.5;
  // Localization mode: a relocalization on the long-term map is on probation for
  // relocalization_probation_s seconds (0 turns the re-check off). Meanwhile, at most once
  // an off_map_relocalization_interval_s, the whole map is searched again; a pose found
  // more than rival_pose_distance_m away with at least relocalization_recheck_margin
  // times the tracked pose's long-term inliers replaces it, and what was made since the
  // relocalization is dropped: a look-alike explains part of the view, the true place
  // all of it, and a few frames on a new search finds the true place with more support.
  double relocalization_probation_s = 5.0;
  double relocalization_recheck_margin = 1.25;
  // Keyframes (ORB-SLAM2 RGB-D rules): a new one when the tracked inliers fall below
  // this share of the reference keyframe's points, or too few close points are tracked
  // (and more than 15 are: ORB-SLAM2's frame-count rules only ever add to these, with
  // its mapping thread idle, so none is needed here).
  double keyframe_tracked_ratio = 0.75;
  // Depth under which a point counts as "close" (accurately measured); 0 = take the
  // median feature depth of the first frame, clamped to [3, 25] m.
  double close_depth_m = 0;
  // Local bundle adjustment over the latest keyframes.
  bool local_bundle_adjustment = true;
  int local_ba_keyframes = 7;
  // In localization too (a run on a loaded long-term map), with the loaded map's points
  // held where they are: they anchor the run's keyframes, and the run's own points, which
  // carry its tracking wherever the loaded map is thin (what a judging mode left out of
  // it: every moveable object), are refined as a mapping run's are.
  bool localization_bundle_adjustment = true;
  // The robust pose optimisation of every tracking stage and the local bundle
  // adjustment; their `bf` is set from depth_sigma_at_1m, and the adjustment runs on one
  // thread (Ceres's threads would sum in another order each run).
  PoseOptimizerOptions pose_optimizer;
  BundleAdjustmentOptions bundle_adjustment;
  // Instance judgement (step 3): a feature is moving when its 3-D position disagrees
  // with its match (map point, or the same instance's feature motion_baseline_s back) by more
  // than moving_distance_m + moving_distance_per_m * depth; without depth, when its
  // reprojection error exceeds moving_reprojection_px (times the level's scale).
  double moving_distance_m = 0.05;
  double moving_distance_per_m = 0.02;
  double moving_reprojection_px = 6.0;
  double motion_baseline_s = 0.3;
  // An instance with at least min_points_to_judge measured features is moving when at
  // least moving_share_threshold of them move: a majority, since a few mismatches on
  // a parked car must not make it a moving one (all points of a moving rigid object move).
  int min_points_to_judge = 4;
  double moving_share_threshold = 0.5;
  // A background feature within this many pixels (>= 0) of the mask of an instance kept
  // out of the pose and map (moving, or not judged yet) is kept out with it (mutual and
  // oracle; mask-moveable drops what lies on the masks): a corner on a moving object's
  // outline moves with the object, yet its keypoint often falls just outside the mask
  // (figures: docs/tuning.md, "The tracker").
  int instance_margin_px = 15;
  // Whether instance_margin_px is counted in pixels of the feature's pyramid level
  // (instance_margin_px times the level's scale, in the image's pixels): a feature found
  // at a coarser level is a corner, and has a descriptor patch, that many times larger,
  // so a mover's outline reaches into it from that much further away. 15 px at the
  // finest level is about an ORB patch's half-width at every level (15 to 54 px).
  bool instance_margin_scales_with_level = true;
  // Whether the margin also goes around instances kept out because they are not judged
  // yet, which may be moving (else only around those judged moving). Without it the
  // outline of a mover that has just come into view, not judged yet, enters the pose;
  // with it a sitting office loses background near people in a map's first frames
  // (figures: docs/results.md, "The wider margin as the default").
  bool instance_margin_around_unjudged = true;
  // Whether that margin also goes around them in a run's first motion_baseline_s (and a
  // map's begun anew), when no instance can be judged yet and every person, chair and
  // parked car is kept out. With it the margins take part of a street's background, and
  // an object the segmenter missed (a truck moving beside the camera) can then outnumber
  // what is left of it at the second frame. Without it the first keyframe maps the
  // background there too, and those points wait for the verdict on the instance whose
  // outline they may be (MapPoint::bordered_unjudged_instance), as a walker's outline
  // must (docs/results.md, "The outline that waits for the verdict").
  bool instance_margin_around_unjudged_at_start = false;
  // Whether an instance judged still for the first time is mapped in the keyframes of a
  // map's first motion_baseline_s that kept it out, not judged yet (those within what
  // the verdict compared), its points matched across them as tracking would have matched
  // them. Without it a map's founding keyframes hold nothing of the people, chairs and
  // cars in view, and the map gains them only at the next keyframe, which in an office
  // comes late. Only there: later an instance that comes into view is kept out of few
  // keyframes in an office, but of several in a street (a keyframe on most frames), and
  // mapped from all of them on one frame's still verdict, a wrong verdict costs more
  // than the map gains (docs/results.md, "Mapping an instance on its verdict").
  bool map_instances_on_verdict = true;
  // Read by the frame pipeline (mutual/frame_pipeline.h), not the tracker: once the first
  // motion_baseline_s of a pass is over and an instance kept out of it unjudged is judged
  // still, those frames are tracked again from the pass's start by a fresh tracker that
  // knows the verdicts (PresetStartVerdicts). Nothing can be judged in a map's first
  // baseline, so whatever stood still in view there (people sitting at a desk) is
  // otherwise missing from the founding keyframes, and the map begins on the rest alone.
  bool retrack_map_start = true;
  // An instance of a class that does not move (not on the moveable shortlist: a traffic
  // light, a bench, a hydrant) is judged moving only on at least this many measured
  // points. Its few matches are often wrong in a consistent way (a traffic light's three
  // lamps match each other), which would keep it "moving" for as long as the camera
  // looks at it, e.g. while standing at the light; a large object the segmenter
  // mislabels still shows enough points when it really moves.
  int min_points_to_move_fixed_class = 20;
  // An instance measured moving on moving_streak_frames frames in a row (none more than
  // moving_memory_s apart) stays moving, until it is seen again with at least
  // min_points_to_clear_moving measured features (or an eighth of its features, when that
  // is fewer). A walker matched on a handful of points for one frame would otherwise
  // enter the map, and a pair walking together then drags the coarse pose with it (the
  // failure seen on in_front walking scenes); a one-frame blip on a still object does not
  // start a streak.
  int moving_streak_frames = 5;
  double moving_memory_s = 1.0;
  int min_points_to_clear_moving = 20;
  // Map points younger than motion_baseline_s do not judge an instance (a walker covers
  // 1-2 cm per frame, under the threshold) until the instance has been judged static
  // over a full baseline on this many frames in a row (a parked car stays parked).
  int static_frames_to_trust_young_points = 10;
  // How instances are judged: from the depth of every instance pixel
  // (DepthJudgementOptions), or, with false, from re-found sparse features as the paper
  // does (the options above from moving_distance_m on). Without depth images, always the
  // latter. moving_distance_m, moving_distance_per_m, motion_baseline_s,
  // min_points_to_move_fixed_class and moving_memory_s serve both.
  bool judge_by_depth = true;
  DepthJudgementOptions depth_judgement;
  // Long-term map export: points seen in at least this many keyframes.
  int long_term_min_observations = 2;
  // Long-term map export of the judging modes: keep the points made on instances of fixed
  // classes (tables, screens, plants, traffic lights; core/coco.h) and not seen mostly on
  // moveable ones, as a map of only what stays put allows (DESIGN.md: no point on a
  // moveable object). Without, every point on an instance is left out, and an office's
  // desks and screens with it: pass 2 then localizes on walls and floor alone.
  bool long_term_map_keeps_fixed_instances = true;
  // The first keyframe needs this many features with depth that may enter the map (in
  // mutual mode not those on moveable instances that are not judged yet).
  int min_initial_map_features = 100;
  // A young map (at most reset_map_keyframes keyframes) that stays lost for
  // reset_map_after_lost_s is dropped, and the next frame with enough features begins a
  // new one: it was begun on a view the scene soon hid (people walking close in front of
  // the camera at the start) and cannot relocalize where it never saw anything. ORB-SLAM2
  // drops a map lost with at most 5 keyframes at once; waiting first lets a short
  // occlusion relocalize. 0 keyframes = never. Never in localization mode.
  int reset_map_keyframes = 5;
  double reset_map_after_lost_s = 1.0;
  // Pose of the first frame when no map is loaded (the map's frame).
  Eigen::Isometry3d initial_T_wc = Eigen::Isometry3d::Identity();
  // Fill FrameResult::feature_records (costs a few kB per frame; off for plain runs).
  bool record_features = false;
};

class Tracker {
 public:
  Tracker(const PinholeCamera& camera, const TrackerOptions& options = {});
  ~Tracker();
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;

  // Localization mode: `map`'s points become fixed points of the map. Throws
  // segslam::Error if the map was built with another camera.
  void LoadLongTermMap(const LongTermMapData& map, const std::string& origin);

  // --- The per-frame steps, in this order. ---
  // Throws segslam::Error if the frame's images have the wrong type or size.
  void BeginFrame(const RgbdFrame& frame);
  // Drops features on moveable-class instances (mask-moveable mode), before the coarse pose.
  void DropMoveableFeatures(const FrameInstances& instances);
  // Step 1. Returns the coarse T_wc, or nullopt when the frame cannot be tracked or
  // relocalized (then the frame is lost and the later steps only record that).
  std::optional<Eigen::Isometry3d> EstimateCoarsePose();
  // After step 1: the coarse pose came from a relocalization, not from the last frame's
  // pose, so the two need not be in one frame (off the long-term map it may jump).
  bool CoarsePoseRelocalized() const;
  // Step 3 with the refined masks of this frame. Where DESIGN.md measures motion with
  // the coarse pose, this measures it with the pose of the background (the coarse
  // matches, rejected ones too, of the features on no moveable-class instance), when at
  // least min_tracking_inliers of them fit; else with the coarse pose. Instances that
  // fill the view pull the coarse pose along, and then agree with it whether they move
  // or not. With `given_moving_ids` (verdicts decided elsewhere, e.g. the bench's oracle)
  // the motion is still measured and recorded, but every instance is judged, moving
  // exactly when its id is in the set.
  std::vector<InstanceJudgement> JudgeInstances(const FrameInstances& instances,
                                                const std::unordered_set<std::uint16_t>* given_moving_ids = nullptr);
  // Verdicts given in hindsight for a pass's first frames (TrackerOptions::
  // retrack_map_start): on frames stamped before `until_stamp_s`, an instance its own
  // evidence has not judged yet takes its verdict from `moving_by_id` (true: moving)
  // where that has one. Its own verdict, once it has one, wins.
  void PresetStartVerdicts(std::unordered_map<std::uint16_t, bool> moving_by_id, double until_stamp_s);
  // Step 4. Without JudgeInstances it equals the coarse pose.
  std::optional<Eigen::Isometry3d> EstimateFinePose();
  // Step 5; returns the frame's result (timings, status, judgements).
  FrameResult UpdateMaps();

  // The long-term map (DESIGN.md core step 5): background points and, with
  // long_term_map_keeps_fixed_instances, those of fixed-class instances; or every point
  // for `include_instances` (the plain baseline). In localization mode: the loaded map as is.
  LongTermMapData ExportLongTermMap(bool include_instances) const;

  // The current map; a map reset (FrameResult::map_reset) replaces it, so a reference
  // is good until the next frame.
  const Map& map() const { return *map_; }
  const PinholeCamera& camera() const { return camera_; }
  const TrackerOptions& options() const { return options_; }
  bool localization_mode() const { return localization_mode_; }

 private:
  struct Impl;
  PinholeCamera camera_;
  TrackerOptions options_;
  std::unique_ptr<Map> map_;
  std::unique_ptr<Impl> impl_;
  bool localization_mode_ = false;
  std::optional<LongTermMapData> loaded_map_;
};

}  // namespace segslam::slam
