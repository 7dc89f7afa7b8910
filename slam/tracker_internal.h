// The tracker's working state, shared by the files that implement slam/tracker.h:
//   tracker.cpp             the per-frame steps of the public interface
//   frame_tracking.cpp      matching by projection and descriptors, the tracking stages
//                           (motion model, reference keyframe, local map), relocalization
//   instance_judgement.cpp  moving or static, per instance (the paper's step 3)
//   local_mapping.cpp       keyframes, new points, culling, local bundle adjustment
// Private to slam/: nothing outside it includes this header.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "slam/bundle_adjustment.h"
#include "slam/descriptor_index.h"
#include "slam/map.h"
#include "slam/pose_optimizer.h"
#include "slam/tracker.h"

namespace segslam::slam {

using Clock = std::chrono::steady_clock;

inline double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Keypoint indices bucketed by position, for searches in a window around a projection.
class FeatureGrid {
 public:
  static constexpr int kCellPx = 16;

  void Build(const std::vector<cv::KeyPoint>& keypoints, int width, int height) {
    cols_ = (width + kCellPx - 1) / kCellPx;
    rows_ = (height + kCellPx - 1) / kCellPx;
    cells_.assign(static_cast<size_t>(cols_ * rows_), {});
    for (size_t i = 0; i < keypoints.size(); ++i) {
      const int c = std::clamp(static_cast<int>(keypoints[i].pt.x) / kCellPx, 0, cols_ - 1);
      const int r = std::clamp(static_cast<int>(keypoints[i].pt.y) / kCellPx, 0, rows_ - 1);
      cells_[static_cast<size_t>(r * cols_ + c)].push_back(static_cast<int>(i));
    }
  }

  // Indices of keypoints within `radius` of (x, y) whose level lies in [min_level, max_level].
  void Query(const std::vector<cv::KeyPoint>& keypoints, double x, double y, double radius,
             int min_level, int max_level, std::vector<int>* out) const {
    out->clear();
    const int c0 = std::max(0, static_cast<int>(std::floor((x - radius) / kCellPx)));
    const int c1 = std::min(cols_ - 1, static_cast<int>(std::floor((x + radius) / kCellPx)));
    const int r0 = std::max(0, static_cast<int>(std::floor((y - radius) / kCellPx)));
    const int r1 = std::min(rows_ - 1, static_cast<int>(std::floor((y + radius) / kCellPx)));
    const double radius2 = radius * radius;
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        for (int index : cells_[static_cast<size_t>(r * cols_ + c)]) {
          const cv::KeyPoint& kp = keypoints[static_cast<size_t>(index)];
          if (kp.octave < min_level || kp.octave > max_level) continue;
          const double dx = kp.pt.x - x;
          const double dy = kp.pt.y - y;
          if (dx * dx + dy * dy <= radius2) out->push_back(index);
        }
      }
    }
  }

 private:
  int cols_ = 0;
  int rows_ = 0;
  std::vector<std::vector<int>> cells_;
};

// ORB-SLAM's rotation consistency check: the orientation changes of correct matches
// agree, so only the matches in the three most populated histogram bins are kept.
class RotationHistogram {
 public:
  static constexpr int kBins = 30;
  void Add(int feature, float angle_from_deg, float angle_to_deg) {
    float change = angle_to_deg - angle_from_deg;
    if (change < 0) change += 360.0f;
    const int bin = std::min(kBins - 1, static_cast<int>(change * kBins / 360.0f));
    bins_[static_cast<size_t>(bin)].push_back(feature);
  }
  // Features outside the three strongest bins (a bin under 10% of the strongest is
  // dropped too, as ORB-SLAM does).
  std::vector<int> Rejected() const {
    std::array<size_t, kBins> order{};
    for (int i = 0; i < kBins; ++i) order[static_cast<size_t>(i)] = static_cast<size_t>(i);
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return bins_[a].size() > bins_[b].size(); });
    const size_t strongest = bins_[order[0]].size();
    std::vector<int> rejected;
    for (int rank = 0; rank < kBins; ++rank) {
      const auto& bin = bins_[order[static_cast<size_t>(rank)]];
      const bool keep = rank < 3 && bin.size() * 10 >= strongest;
      if (!keep) rejected.insert(rejected.end(), bin.begin(), bin.end());
    }
    return rejected;
  }

 private:
  std::array<std::vector<int>, kBins> bins_;
};

// Whether a depth reading `other` (m, 0 = none) lies on the same surface as `depth`:
// within 5 % plus 2 cm, what a depth edge exceeds. Both judgements use it to keep
// silhouettes, whose depth reads either side of the edge, out of their measurements.
inline bool OnSameSurface(float other, float depth) {
  return other > 0 && std::abs(other - depth) <= 0.05f * depth + 0.02f;
}

// What the judgement of later frames needs to know of a past frame: its instance
// features, their descriptors and world positions.
struct InstanceSnapshot {
  int frame_index = 0;
  double stamp_s = 0;
  std::vector<std::uint16_t> instance;          // per stored feature
  std::vector<Eigen::Vector3d> point_w;         // NaN where no depth
  cv::Mat descriptors;                          // rows = stored features
  // For the judgement from depth (empty when it did not run on that frame): the frame's
  // pose, depth image and each instance's depth samples in the world.
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  cv::Mat depth_m;
  std::map<std::uint16_t, std::vector<Eigen::Vector3d>> depth_samples_w;
};

// A frame's verdict on one instance from its depth samples: how many landed on valid
// depth in the other frame and agree with it, how many it contradicts.
struct DepthVotes {
  int still = 0;
  int moving = 0;
  int measured() const { return still + moving; }
};

// The 3-D displacements measured on one instance. A moving rigid object moves all its
// points the same way; mismatches on a still one scatter. So the object moves only if
// the component-wise median displacement, not just most single points, exceeds the
// threshold.
struct MotionEvidence {
  std::vector<Eigen::Vector3d> displacements;
  std::vector<double> thresholds;
  std::vector<double> spans_s;  // time between the two positions of each displacement

  void Add(const Eigen::Vector3d& displacement, double threshold, double span_s) {
    displacements.push_back(displacement);
    thresholds.push_back(threshold);
    spans_s.push_back(span_s);
  }

  // True when there are no 3-D measurements (reprojection evidence only) or when the
  // median displacement exceeds the median threshold.
  bool ConsensusMoves() const {
    if (displacements.empty()) return true;
    return MedianOf(displacements).norm() > Median(thresholds);
  }

  // The component-wise median velocity of the displacements (world frame, m/s); zero
  // without any.
  Eigen::Vector3d MedianVelocity() const {
    std::vector<Eigen::Vector3d> velocities;
    for (size_t k = 0; k < displacements.size(); ++k) {
      if (spans_s[k] > 0) velocities.push_back(displacements[k] / spans_s[k]);
    }
    return velocities.empty() ? Eigen::Vector3d::Zero() : MedianOf(velocities);
  }

 private:
  static double Median(std::vector<double> values) {
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
  }
  static Eigen::Vector3d MedianOf(const std::vector<Eigen::Vector3d>& vectors) {
    Eigen::Vector3d median;
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<double> component;
      component.reserve(vectors.size());
      for (const Eigen::Vector3d& v : vectors) component.push_back(v[axis]);
      median[axis] = Median(std::move(component));
    }
    return median;
  }
};

// What the judgement remembers of one instance between frames.
struct InstanceMotionMemory {
  int moving_frames = 0;  // measured moving, frames in a row (none moving_memory_s apart)
  double last_moving_stamp_s = -1e9;
  int static_frames = 0;  // judged static over a full baseline, frames in a row
  // The judgement from depth: log-odds of moving (DepthJudgementOptions), and when a
  // frame last measured the instance.
  double moving_log_odds = 0;
  double last_measured_stamp_s = -1e9;
};

// A moveable instance with no verdict yet: kept out of the fine pose and the map until
// it is judged (KeepOutOfPoseAndMap).
inline bool KeptOutUnjudged(const InstanceJudgement& judgement) {
  return judgement.moveable_class && !judgement.judged && !judgement.moving;
}

struct WorkingFrame {
  int index = -1;
  double stamp_s = 0;
  cv::Mat color_bgr;
  cv::Mat depth_m;
  FrameFeatures features;
  FeatureGrid grid;
  std::vector<MapPoint*> points;        // match per feature (nullptr = none)
  std::vector<bool> outlier;            // match rejected by the last pose optimisation
  std::vector<MapPoint*> rejected;      // outlier matches removed before local-map search
  std::vector<std::uint16_t> instance;  // instance id per feature, 0 = background
  std::vector<bool> excluded;           // moving / unjudged moveable: not for fine pose or map
  std::vector<bool> on_moveable;        // on an instance of a moveable class
  // For a background feature, the instance whose mask lies within
  // TrackerOptions::instance_margin_px (scaled to the feature's level where
  // instance_margin_scales_with_level; 0 = none), or whose outline its map point was made
  // on (MapPoint::bordered_unjudged_instance): kept out with that instance.
  std::vector<std::uint16_t> near_instance;
  // Instances kept out of the fine pose and map on this frame (moving, or not judged yet).
  std::set<std::uint16_t> kept_out;
  // The judgement from depth: each instance's interior depth samples, camera frame.
  std::map<std::uint16_t, std::vector<Eigen::Vector3d>> depth_samples_c;
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
};

struct Tracker::Impl {
  Impl(const PinholeCamera& cam, const TrackerOptions& opts, Map* m)
      : camera(cam), options(opts), map(m), extractor(opts.orb) {
    bf = 1.0 / options.depth_sigma_at_1m;
  }

  const PinholeCamera camera;
  const TrackerOptions options;
  Map* map;
  OrbExtractor extractor;
  double bf = 0;
  double close_depth_m = 0;

  WorkingFrame current;
  WorkingFrame last;
  bool have_last = false;
  std::optional<Eigen::Isometry3d> velocity;  // T_cw(t-1) * T_cw(t-2)^-1
  Keyframe* reference_keyframe = nullptr;
  int last_keyframe_frame = -1000;
  int last_relocalization_frame = -1000;
  bool initialized = false;
  // Stamp of the first frame of this state: the run, or a map begun anew after a reset.
  double first_frame_stamp_s = std::numeric_limits<double>::quiet_NaN();
  // The current frame lies in the map's first motion_baseline_s, when no instance can be
  // judged yet (the depth judgement needs a frame a baseline back to see one still).
  bool AtMapStart() const { return current.stamp_s - first_frame_stamp_s < options.motion_baseline_s - 1e-6; }
  bool pending_first_keyframe = false;
  bool last_status_lost = false;
  double lost_since_s = -1;  // stamp of the first frame of the current run of lost frames
  bool reset_map = false;    // drop the map once this frame is done
  bool localization_mode = false;
  // Localization mode: the last frame was off the long-term map (FrameResult::
  // on_long_term_map); the first frame and the first point made since; when relocalizing
  // on the map was last tried (at most once an off_map_relocalization_interval_s).
  bool off_long_term_map = false;
  int off_map_since_frame = 0;
  std::uint64_t first_point_off_map = 0;
  double last_off_map_relocalization_s = -1e9;
  // Localization mode: the last relocalization's probation (TrackerOptions::
  // relocalization_probation_s), which began at last_relocalization_frame: when it ends,
  // the first point made since it began, and when the whole map was last searched again.
  double probation_until_s = -1e9;
  std::uint64_t probation_first_point = 0;
  double last_probation_check_s = -1e9;
  // The loaded map's points and their descriptor index (Relocalize), built at the first
  // relocalization of a localization run.
  std::vector<MapPoint*> long_term_points;
  std::unique_ptr<DescriptorIndex> long_term_index;
  // The run's own points and their index, rebuilt when the map has gained or purged
  // points since (OwnPointIndex): a lost run tries every frame on an unchanged map.
  std::vector<MapPoint*> own_points;
  std::unique_ptr<DescriptorIndex> own_index;
  std::uint64_t own_index_upcoming_point_id = 0;
  size_t own_index_map_size = 0;
  std::deque<InstanceSnapshot> history;
  std::map<std::uint16_t, InstanceMotionMemory> motion_memory;  // per instance id
  // Tracker::PresetStartVerdicts.
  std::unordered_map<std::uint16_t, bool> preset_moving;
  double preset_until_s = -std::numeric_limits<double>::infinity();
  std::vector<MapPoint*> recent_points;
  // Points made on the outline of an instance not judged yet (MapPoint::
  // bordered_unjudged_instance), by instance: they wait for its verdict.
  std::map<std::uint16_t, std::vector<MapPoint*>> waiting_outlines;
  // Releases the outline of an instance judged still, or marks it bad if judged moving.
  void SettleWaitingOutlines(const std::vector<InstanceJudgement>& judgements);
  // The current frame's colour at a keypoint, RGB.
  std::array<std::uint8_t, 3> ColorAt(const cv::KeyPoint& keypoint) const;
  // Keyframes of the map's first motion_baseline_s that kept an instance out before its
  // first verdict, oldest first, by instance (TrackerOptions::map_instances_on_verdict).
  std::map<std::uint16_t, std::vector<Keyframe*>> keyframes_before_verdict;
  // Matches each of `points` to the nearest descriptor (within strict_descriptor_distance)
  // among the `candidates` of `features`, seen at T_cw, that lie where it projects within
  // the reprojection error an inlier may have (depth as a stereo coordinate); one feature
  // per point. Per point: the feature's index, or -1.
  std::vector<int> MatchByProjection(const std::vector<MapPoint*>& points, const Eigen::Isometry3d& T_cw,
                                     const FrameFeatures& features, const std::vector<int>& candidates) const;
  // Maps each instance judged still for the first time in the keyframes of
  // keyframes_before_verdict made since `evidence_since_s`, the start of what the
  // verdict compared, and matches the points into the current frame; forgets the
  // keyframes of an instance judged moving.
  void MapInstancesOnTheirVerdict(const std::vector<InstanceJudgement>& judgements, double evidence_since_s);
  int keyframes_since_purge = 0;

  // Per-frame state.
  bool coarse_ok = false;
  bool pose_jumped = false;  // relocalized away from the pose tracking gave (off the map)
  bool fine_ok = false;
  bool judged = false;
  FrameResult result;
  Clock::time_point frame_start;
  // Features DropMoveableFeatures() removed from `current` (record_features only).
  std::vector<FeatureRecord> dropped_moveable_records;

  // One record per feature of the frame (TrackerOptions::record_features).
  std::vector<FeatureRecord> FeatureRecords() const;
  bool last_lost() const { return last_status_lost; }

  // ------------------------------------------- matching (frame_tracking.cpp)

  // The observations of `frame`'s matched features (without the excluded ones).
  std::vector<PoseObservation> Observations(const WorkingFrame& frame,
                                            std::vector<int>* feature_of_observation,
                                            bool skip_excluded) const;

  // The observations of the features for which `match(i)` gives a map point.
  template <typename MatchOf>
  std::vector<PoseObservation> ObservationsOf(const WorkingFrame& frame, std::vector<int>* feature_of_observation,
                                              const MatchOf& match) const {
    std::vector<PoseObservation> observations;
    feature_of_observation->clear();
    const auto& inverse_sigma2 = extractor.inverse_level_sigma2();
    for (size_t i = 0; i < frame.points.size(); ++i) {
      const MapPoint* point = match(i);
      if (point == nullptr || point->bad) continue;
      const cv::KeyPoint& kp = frame.features.keypoints[i];
      PoseObservation observation;
      observation.point_w = point->position_w;
      observation.pixel = Eigen::Vector2d(kp.pt.x, kp.pt.y);
      const float depth = frame.features.depth_m[i];
      if (depth > 0) observation.right_u = kp.pt.x - bf / depth;
      observation.information = inverse_sigma2[static_cast<size_t>(kp.octave)];
      observations.push_back(observation);
      feature_of_observation->push_back(static_cast<int>(i));
    }
    return observations;
  }

  int OptimizeCurrentPose(bool skip_excluded, bool discard_outliers);
  MapPoint* MatchedPoint(size_t i) const;
  int BestCandidate(const OrbDescriptor& descriptor, const std::vector<int>& candidates,
                    int max_distance, float ratio) const;
  int SearchLastFrame(double radius_px);
  bool IsOccluded(const Eigen::Vector2d& uv, double z) const;
  int SearchLocalMap(double radius_factor);
  void ClearMatches();
  void MarkCurrentMatched();
  // The current frame's pose and matches, to go back to when a second search loses.
  struct SavedMatches {
    Eigen::Isometry3d T_cw;
    std::vector<MapPoint*> points;
    std::vector<MapPoint*> rejected;
    std::vector<bool> outlier;
  };
  SavedMatches SaveMatches() const;
  void RestoreMatches(const SavedMatches& saved);

  // ------------------------------------------- tracking stages (frame_tracking.cpp)

  bool TrackWithMotionModel();
  bool TrackReferenceKeyframe();
  // The frame after the map's first: no velocity yet (frame_tracking.cpp says why both).
  bool TrackWithoutVelocity();
  bool TrackLocalMap(int min_inliers, double radius_factor);
  bool InitializeMap();
  struct RelocalizationHypothesis {
    Eigen::Isometry3d T_cw;
    std::vector<int> matches;  // RANSAC's consensus: rows of Relocalize()'s match list
  };
  // What a relocalization does with two poses far apart that both hold up: a frame with
  // nothing else to go on stays lost; a re-check, which holds a tracked pose to weigh
  // against, takes the stronger (RecheckRelocalization).
  enum class RivalPolicy { kStayLostWhenAmbiguous, kTakeStronger };
  // Against every map point, or with `long_term_only` against the loaded map's.
  bool Relocalize(bool long_term_only, RivalPolicy rival_policy = RivalPolicy::kStayLostWhenAmbiguous);
  std::vector<RelocalizationHypothesis> RivalPoses(const std::vector<std::pair<int, MapPoint*>>& matched,
                                                   const std::vector<cv::Point3f>& object_points,
                                                   const std::vector<cv::Point2f>& image_points) const;
  int TrackFromHypothesis(const RelocalizationHypothesis& hypothesis,
                          const std::vector<std::pair<int, MapPoint*>>& matched);
  const DescriptorIndex& OwnPointIndex();
  // Off the long-term map: relocalizes on it, and on success drops what was made off it.
  bool RelocalizeOffMap();
  // The current frame's inliers that stay when the run's own points from
  // `first_dropped_point` on are dropped; with 0, its inliers on the long-term map.
  int InliersKeptWhenDroppingFrom(std::uint64_t first_dropped_point) const;
  int LongTermInliers() const { return InliersKeptWhenDroppingFrom(0); }
  // Drops the run's own points from `first_point` on and its keyframes from
  // `since_frame` on, made in a frame just found wrong, and the current frame's matches
  // to them.
  void DropWorkSince(std::uint64_t first_point, int since_frame);
  // Starts the probation of a relocalization made at the current frame.
  void BeginProbation();
  // On probation and tracked: searches the whole long-term map again and takes a pose
  // found elsewhere with markedly more support (TrackerOptions::
  // relocalization_probation_s); true when it did. Else the frame is left as tracked.
  bool RecheckRelocalization();
  // Localization mode, after the fine pose: counts its inliers on the long-term map into
  // the result and notes when the run leaves the map.
  void NoteLongTermMapMatches();

  // ------------------------------------------- judgement helpers (instance_judgement.cpp)

  std::optional<Eigen::Isometry3d> BackgroundPose(const std::unordered_set<std::uint16_t>& moveable_ids) const;
  bool OnDepthEdge(size_t i) const;
  double MovingDistanceThreshold(double depth) const;
  int MotionAgainstPoint(size_t i, const MapPoint* point, const Eigen::Isometry3d& T_wc,
                         MotionEvidence* evidence) const;
  InstanceSnapshot Snapshot() const;
  // Drops the snapshots a frame at `stamp_s` or later no longer needs: it measures
  // against the newest one at least motion_baseline_s older than it.
  void ForgetSnapshotsBefore(double stamp_s);

  // Returns whether the remembered frame measured against lies a full baseline back. A
  // "static" verdict needs it: over one frame a walker moves less than the depth noise.
  bool MotionAgainstHistory(std::uint16_t id, const std::vector<int>& features, const Eigen::Isometry3d& T_wc,
                            InstanceJudgement* judgement, MotionEvidence* evidence) const;

  // ------------------------------------------- judgement (instance_judgement.cpp)
  // JudgeInstances() in steps: which features lie on which instance; what this frame
  // measures of each instance's motion; the verdict on that measurement; what the
  // instance's recent frames add to it; and what a verdict keeps out of the pose and map.

  // The instance nearest to pixel (x, y) within margin_px; 0 = none. The integral
  // image (CV_32S, one row and column more than ids) sums ids != 0.
  std::uint16_t InstanceNear(const cv::Mat& ids, const cv::Mat& instance_pixels_integral, int x, int y,
                             int margin_px) const;
  std::map<std::uint16_t, std::vector<int>> LabelFeatures(const cv::Mat& ids);
  bool MeasureInstanceMotion(std::uint16_t id, const std::vector<int>& features,
                             const Eigen::Isometry3d& T_wc, bool trust_young_points,
                             InstanceJudgement* judgement, MotionEvidence* evidence) const;
  void DecideMotion(bool full_baseline, const MotionEvidence& evidence, InstanceJudgement* judgement) const;
  void ApplyMotionMemory(bool full_baseline, InstanceJudgement* judgement, InstanceMotionMemory* memory) const;
  void KeepOutOfPoseAndMap(const InstanceJudgement& judgement, const std::vector<int>& features);

  // ------------------------------------------- judgement from depth (depth_judgement.cpp)

  // Whether this frame is judged from depth (TrackerOptions::judge_by_depth, and a depth
  // image to judge with).
  bool JudgesByDepth() const { return options.judge_by_depth && !current.depth_m.empty(); }
  // Fills current.depth_samples_c: up to samples_per_instance interior pixels of each
  // instance with depth, back-projected.
  void SampleInstanceDepth(const cv::Mat& ids);
  // Counts into *votes how many of the world points `points_w`, each moved by `offset_w`
  // (world frame, m) and seen from T_cw in a frame with depth `depth_m`, agree with that
  // depth and how many lie before it (the depth there is farther: what was there has
  // gone). Points behind something are not counted.
  void VoteAgainstDepth(const std::vector<Eigen::Vector3d>& points_w, const Eigen::Isometry3d& T_cw,
                        const cv::Mat& depth_m, const Eigen::Vector3d& offset_w, DepthVotes* votes) const;
  // This frame's measurement of instance `id` against the remembered frame `past`, in
  // both directions; the counts go to judgement->num_points / num_moving_points.
  DepthVotes MeasureDepthMotion(std::uint16_t id, const Eigen::Isometry3d& T_wc, const InstanceSnapshot& past,
                                InstanceJudgement* judgement) const;
  // The votes of instance `id`'s depth samples in both directions, as MeasureDepthMotion,
  // on the hypothesis that it moved by `displacement_w` (world frame) since `past`.
  DepthVotes VoteOnDisplacement(std::uint16_t id, const Eigen::Isometry3d& T_wc, const InstanceSnapshot& past,
                                const Eigen::Vector3d& displacement_w) const;
  // Whether depth refutes the motion the sparse features measured (`evidence`): moved
  // that way since `past`, the instance's depth samples are contradicted more often than
  // they are standing still (`still`, the votes on that).
  bool DepthRefutesSparseMotion(std::uint16_t id, const Eigen::Isometry3d& T_wc, const InstanceSnapshot& past,
                                const MotionEvidence& evidence, const DepthVotes& still) const;
  // Whether this frame's votes show the instance moving.
  bool DepthSeesMotion(const DepthVotes& votes, const InstanceJudgement& judgement) const;
  // The verdict: whether this frame saw the instance move (its depth or its sparse
  // features) or, measured on enough samples over a full baseline, still, added to the
  // instance's log-odds of moving.
  void DecideFromDepth(const DepthVotes& votes, bool full_baseline, bool sees_motion, InstanceJudgement* judgement,
                       InstanceMotionMemory* memory) const;
  void KeepOutNearbyBackground(std::uint16_t id);

  // ------------------------------------------- mapping (local_mapping.cpp)

  bool NeedNewKeyframe() const;
  void CreateKeyframe();
  void CullRecentPoints(const Keyframe* keyframe);
  std::vector<Keyframe*> LocalWindow() const;

  // Local bundle adjustment's problem over a window: its keyframes and the good points
  // they see are free; the other keyframes that see those points hold the window in
  // place, and so does the map's first keyframe.
  struct LocalBaProblem {
    std::map<Keyframe*, int, KeyframeIdLess> keyframe_index;  // into `keyframes`
    std::vector<BaKeyframe> keyframes;
    std::vector<MapPoint*> points;  // ascending id
    std::vector<Eigen::Vector3d> positions;  // of `points`
    std::vector<bool> constant;              // of `points`: a loaded map's, held fixed
    std::vector<BaObservation> observations;
    std::vector<std::pair<MapPoint*, Keyframe*>> observation_owner;  // of `observations`
  };
  LocalBaProblem MakeLocalBaProblem(const std::vector<Keyframe*>& window) const;
  void ApplyLocalBa(const LocalBaProblem& problem, const BundleAdjustmentResult& adjusted);
  void LocalBundleAdjustment();
  void PurgeBadPoints();
};

}  // namespace segslam::slam
